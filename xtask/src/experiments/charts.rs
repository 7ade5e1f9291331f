//! Charts for the reports: log-log convergence plots (plotters into a buffer, encoded with
//! image 0.25), and the font every text of the reports is drawn in.
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::Path;

static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans.ttf");

pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// One curve of a plot.
pub struct Series {
    pub label: String,
    /// (x, mean, std), x ascending.
    pub points: Vec<(f64, f64, f64)>,
}

pub const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(255, 127, 14),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Log-log panel of relMSE curves with a dashed horizontal line at `floor` (reference error).
fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    caption: &str,
    x_label: &str,
    series: &[Series],
    floor: Option<f64>,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let pts = series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, m, sd) in pts {
        if x > 0.0 && m > 0.0 {
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min((m - sd).max(m * 0.5));
            y1 = y1.max(m + sd);
        }
    }
    if let Some(f) = floor.filter(|f| *f > 0.0) {
        y0 = y0.min(f);
        y1 = y1.max(f);
    }
    if x0 > x1 {
        (x0, x1, y0, y1) = (1.0, 10.0, 1e-3, 1.0);
    }
    let (x0, x1) = (x0 / 1.3, x1 * 1.3);
    let (y0, y1) = (y0 / 1.5, y1 * 1.5);
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let mut chart = ChartBuilder::on(area)
        .caption(caption, ("sans-serif", 18))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_labels(6)
        .y_labels(6)
        .light_line_style(RGBColor(235, 235, 235))
        .x_desc(x_label)
        .y_desc("relMSE (unlit pixels)")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_label_formatter(&|v| {
            if *v >= 10.0 {
                format!("{v:.0}")
            } else {
                format!("{v:.2}")
            }
        })
        .draw()
        .map_err(e)?;
    for (k, s) in series.iter().enumerate() {
        let colour = PALETTE[k % PALETTE.len()];
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter(|p| p.0 > 0.0 && p.1 > 0.0)
            .map(|p| (p.0, p.1))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
            .map_err(e)?
            .label(s.label.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
            .map_err(e)?;
        chart
            .draw_series(
                s.points
                    .iter()
                    .filter(|p| p.0 > 0.0 && p.1 - p.2 > 0.0 && p.2 > 0.0)
                    .map(|&(x, m, sd)| {
                        PathElement::new(vec![(x, m - sd), (x, m + sd)], colour.stroke_width(1))
                    }),
            )
            .map_err(e)?;
    }
    if let Some(f) = floor.filter(|f| *f > 0.0) {
        let grey = RGBColor(120, 120, 120);
        let n = 40;
        let segs = (0..n).step_by(2).map(move |i| {
            let a = x0 * (x1 / x0).powf(i as f64 / n as f64);
            let b = x0 * (x1 / x0).powf((i + 1) as f64 / n as f64);
            PathElement::new(vec![(a, f), (b, f)], grey.stroke_width(1))
        });
        chart
            .draw_series(segs)
            .map_err(e)?
            .label("reference's own error (est.)")
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], grey.stroke_width(1))
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(e)?;
    Ok(())
}

/// relMSE vs spp (left) and vs seconds (right), log-log, one PNG.
pub fn convergence_plot(
    path: &Path,
    title: &str,
    vs_spp: &[Series],
    vs_seconds: &[Series],
    seconds_label: &str,
    floor: Option<f64>,
) -> Result<(), String> {
    register_font();
    let (w, h) = (1200u32, 480u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let root = root
            .titled(title, ("sans-serif", 20))
            .map_err(|e| e.to_string())?;
        let (l, r) = root.split_horizontally(w / 2);
        panel(&l, "equal spp", "samples per pixel", vs_spp, floor)?;
        panel(&r, "equal time", seconds_label, vs_seconds, floor)?;
        root.present().map_err(|e| e.to_string())?;
    }
    render_core::output::write_png_rgb8(path, w, h, &buf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plots_draw() {
        let dir = std::env::temp_dir().join(format!("xtask-plot-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let s = vec![Series {
            label: "A".into(),
            points: vec![(1.0, 0.1, 0.01), (4.0, 0.025, 0.002)],
        }];
        convergence_plot(&dir.join("p.png"), "t", &s, &s, "seconds", Some(0.001)).unwrap();
        assert!(image::open(dir.join("p.png")).is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
