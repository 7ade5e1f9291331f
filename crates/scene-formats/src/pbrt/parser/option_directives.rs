//! Rendering options: `Sampler` and `PixelFilter` become the scene's render hints (the command
//! line uses them unless told otherwise); what this renderer does not model (`Integrator` and
//! the other renderer settings, `ColorSpace`, `Option`, participating media and `Attribute`
//! defaults) is read whole and warned about.
use super::Parser;
use render_core::error::SceneError;
use render_core::filter::PixelFilter;
use render_core::scene_hints::sampler_for_pbrt;

impl Parser<'_> {
    /// `Sampler`: its type (mapped onto ours) and `pixelsamples` become render hints; the
    /// strategy, the spp and the seed still come from the command line.
    pub(super) fn sampler_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("Sampler", line)?;
        let p = self.params()?;
        let spp = p.int("pixelsamples", 16).map_err(|m| self.err(line, m))?;
        self.unused(
            &format!("Sampler \"{ty}\""),
            &p,
            &[
                "seed",
                "dimensions",
                "jitter",
                "randomization",
                "xsamples",
                "ysamples",
            ],
        );
        let hints = self.builder.render_hints_mut();
        hints.spp = u32::try_from(spp).ok().filter(|&n| n > 0);
        match sampler_for_pbrt(&ty) {
            Some((s, true)) => hints.sampler = Some(s),
            Some((s, false)) => {
                hints.sampler = Some(s);
                self.warn(
                    line,
                    format!("Sampler \"{ty}\" is not implemented: the {s} sampler is used"),
                );
            }
            None => self.warn(line, format!("Sampler \"{ty}\" is unknown (ignored)")),
        }
        Ok(())
    }

    /// `PixelFilter`: box, triangle, gaussian and mitchell with pbrt-v3's (`xwidth`, `alpha`)
    /// or pbrt-v4's (`xradius`, `sigma`) parameters; a filter we lack is warned about and the
    /// one-pixel box used.
    pub(super) fn pixel_filter_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("PixelFilter", line)?;
        let p = self.params()?;
        let radius_of = |default: f32| -> Result<(f32, f32), String> {
            let v3 = (p.float("xwidth", default)?, p.float("ywidth", default)?);
            if p.has("xradius") || p.has("yradius") {
                Ok((p.float("xradius", default)?, p.float("yradius", default)?))
            } else {
                Ok(v3)
            }
        };
        let default_radius = match ty.as_str() {
            "box" => 0.5,
            "gaussian" => {
                if p.has("alpha") {
                    2.0
                } else {
                    1.5
                }
            }
            _ => 2.0,
        };
        let (rx, ry) = radius_of(default_radius).map_err(|m| self.err(line, m))?;
        if rx != ry {
            self.warn(
                line,
                format!("PixelFilter \"{ty}\": radii {rx} × {ry} differ; {rx} is used for both"),
            );
        }
        let filter = match ty.as_str() {
            "box" | "triangle" => PixelFilter::from_name(&ty, Some(rx)),
            "gaussian" => {
                // pbrt-v3's exp(−α x²) is σ = 1/√(2α).
                let sigma = if p.has("alpha") {
                    let a = p.float("alpha", 2.0).map_err(|m| self.err(line, m))?;
                    if !(a > 0.0 && a.is_finite()) {
                        return Err(
                            self.err(line, format!("PixelFilter: alpha {a} must be positive"))
                        );
                    }
                    1.0 / (2.0 * a).sqrt()
                } else {
                    p.float("sigma", 0.5).map_err(|m| self.err(line, m))?
                };
                if !(sigma > 0.0 && sigma.is_finite()) {
                    return Err(
                        self.err(line, format!("PixelFilter: sigma {sigma} must be positive"))
                    );
                }
                PixelFilter::check_radius(rx).map(|_| PixelFilter::gaussian(rx, sigma))
            }
            "mitchell" => {
                let b = p.float("B", 1.0 / 3.0).map_err(|m| self.err(line, m))?;
                let c = p.float("C", 1.0 / 3.0).map_err(|m| self.err(line, m))?;
                PixelFilter::check_radius(rx).map(|_| PixelFilter::mitchell(rx, b, c))
            }
            _ => {
                self.warn(
                    line,
                    format!(
                        "PixelFilter \"{ty}\" is not implemented: a one-pixel box filter is used"
                    ),
                );
                p.touch("tau");
                Ok(PixelFilter::default())
            }
        }
        .map_err(|m| self.err(line, format!("PixelFilter \"{ty}\": {m}")))?;
        self.unused(
            &format!("PixelFilter \"{ty}\""),
            &p,
            &[
                "xwidth", "ywidth", "xradius", "yradius", "alpha", "sigma", "B", "C",
            ],
        );
        self.builder.render_hints_mut().filter = Some(filter);
        Ok(())
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
