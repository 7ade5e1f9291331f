//! Rendering options and what this renderer does not model: `Sampler` and `PixelFilter` (the
//! command line chooses; each has its own function, the place to honour it), `Integrator` and
//! the other renderer settings, `ColorSpace`, `Option`, participating media and `Attribute`
//! defaults. Each is read whole and warned about.
use super::Parser;
use render_core::error::SceneError;

impl Parser<'_> {
    /// `Sampler`: the strategy, spp and seed come from the command line.
    pub(super) fn sampler_directive(&mut self, line: usize) -> Result<(), SceneError> {
        self.skipped_setting(
            "Sampler",
            line,
            "the strategy, spp and seed come from the command line",
        )
    }

    /// `PixelFilter`: the renderer's pixels are one-pixel boxes.
    pub(super) fn pixel_filter_directive(&mut self, line: usize) -> Result<(), SceneError> {
        self.skipped_setting("PixelFilter", line, "a one-pixel box filter is used")
    }

    /// `Integrator` and the other renderer settings (`Accelerator`, pbrt-v3's
    /// `SurfaceIntegrator`, `VolumeIntegrator`, `Renderer`).
    pub(super) fn renderer_setting(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        let what = match d {
            "Integrator" => {
                "only direct lighting is computed, by the strategy the command line names"
            }
            _ => "ignored",
        };
        self.skipped_setting(d, line, what)
    }

    /// Reads `d "type" params` and warns that `what` is done instead.
    fn skipped_setting(&mut self, d: &str, line: usize, what: &str) -> Result<(), SceneError> {
        let ty = self.string_arg(d, line)?;
        self.params()?;
        self.warn(line, format!("{d} \"{ty}\": {what}"));
        Ok(())
    }

    /// `ColorSpace`: colours are taken as linear RGB.
    pub(super) fn color_space(&mut self, line: usize) -> Result<(), SceneError> {
        let cs = self.string_arg("ColorSpace", line)?;
        self.warn(
            line,
            format!("ColorSpace \"{cs}\": colours are read as linear RGB as given"),
        );
        Ok(())
    }

    /// `Option`: pbrt-v4's rendering options, all ignored.
    pub(super) fn option_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let p = self.params()?;
        for q in &p.params {
            p.touch(&q.name);
        }
        self.warn(line, "Option: rendering options are ignored");
        Ok(())
    }

    /// `MakeNamedMedium` and `MediumInterface`: no volumes here.
    pub(super) fn medium_directive(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        if d == "MakeNamedMedium" {
            let name = self.string_arg(d, line)?;
            self.params()?;
            self.warn(
                line,
                format!("MakeNamedMedium \"{name}\": volumes are not supported (ignored)"),
            );
            return Ok(());
        }
        self.string_arg(d, line)?;
        if self.peek_is_str()? {
            self.string_arg(d, line)?;
        }
        self.warn(line, "MediumInterface: volumes are not supported (ignored)");
        Ok(())
    }

    /// `Attribute`: pbrt-v4's default parameters for later directives, not supported.
    pub(super) fn attribute_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let target = self.string_arg("Attribute", line)?;
        self.params()?;
        self.warn(
            line,
            format!("Attribute \"{target}\": default parameters are not supported (ignored)"),
        );
        Ok(())
    }
}
