//! The sampler and pixel filter a glTF file asks for: `extras.pbrt.sampler` and
//! `extras.pbrt.filter` of its scene (or of the document), as the bisml_cornell conversion and
//! `manylights convert` write them: `{"type": "triangle", "radius_px": 1}` (optional `sigma`,
//! `B`, `C`) and `{"type": "lowdiscrepancy", "pixelsamples": 4}`.
use super::Loader;
use render_core::error::SceneError;
use render_core::filter::PixelFilter;
use render_core::scene_hints::sampler_for_pbrt;
use serde_json::Value;

impl Loader<'_> {
    /// Reads the file's hints into the builder's.
    pub(super) fn read_render_hints(&mut self) -> Result<(), SceneError> {
        let doc = self.doc;
        let scene_extras = doc
            .default_scene()
            .or_else(|| doc.scenes().next())
            .and_then(|s| s.extras().clone());
        let extras = scene_extras.or_else(|| doc.as_json().extras.clone());
        let Some(raw) = extras else { return Ok(()) };
        let Ok(v) = serde_json::from_str::<Value>(raw.get()) else {
            return Ok(());
        };
        let Some(pbrt) = v.get("pbrt") else {
            return Ok(());
        };
        if let Some(s) = pbrt.get("sampler") {
            let ty = s.get("type").and_then(Value::as_str).unwrap_or("");
            match sampler_for_pbrt(ty) {
                Some((sampler, exact)) => {
                    if !exact {
                        self.report.warn(format!("extras.pbrt.sampler \"{ty}\" is not implemented: the {sampler} sampler is used"));
                    }
                    self.builder.render_hints_mut().sampler = Some(sampler);
                }
                None => self
                    .report
                    .warn(format!("extras.pbrt.sampler \"{ty}\" is unknown (ignored)")),
            }
            let spp = s.get("pixelsamples").and_then(Value::as_u64);
            self.builder.render_hints_mut().spp =
                spp.and_then(|n| u32::try_from(n).ok()).filter(|&n| n > 0);
        }
        if let Some(f) = pbrt.get("filter") {
            let filter = filter_of(f).map_err(|m| self.err(format!("extras.pbrt.filter: {m}")))?;
            self.builder.render_hints_mut().filter = Some(filter);
        }
        Ok(())
    }
}

fn filter_of(f: &Value) -> Result<PixelFilter, String> {
    let ty = f.get("type").and_then(Value::as_str).ok_or("no \"type\"")?;
    let number = |key: &str| -> Result<Option<f32>, String> {
        match f.get(key) {
            None => Ok(None),
            Some(x) => x
                .as_f64()
                .map(|v| Some(v as f32))
                .ok_or(format!("{key} is not a number")),
        }
    };
    let radius = number("radius_px")?;
    let filter = PixelFilter::from_name(ty, radius)?;
    Ok(match filter {
        PixelFilter::Gaussian { radius, sigma, .. } => {
            let sigma = number("sigma")?.unwrap_or(sigma);
            if !(sigma > 0.0 && sigma.is_finite()) {
                return Err(format!("sigma {sigma} must be positive"));
            }
            PixelFilter::gaussian(radius, sigma)
        }
        PixelFilter::Mitchell { radius, b, c, .. } => {
            PixelFilter::mitchell(radius, number("B")?.unwrap_or(b), number("C")?.unwrap_or(c))
        }
        other => other,
    })
}

/// The hints as `extras.pbrt` fields, for the writer.
pub fn hints_extras(h: &render_core::scene_hints::RenderHints) -> Option<Value> {
    let mut pbrt = serde_json::Map::new();
    if let Some(s) = h.sampler {
        let mut v = serde_json::json!({ "type": render_core::scene_hints::pbrt_name(s) });
        if let Some(n) = h.spp {
            v["pixelsamples"] = n.into();
        }
        pbrt.insert("sampler".into(), v);
    }
    if let Some(f) = &h.filter {
        let mut v = serde_json::json!({ "type": f.name(), "radius_px": f.radius() });
        for (k, x) in f.parameters() {
            if k != "radius" {
                v[k] = x.into();
            }
        }
        pbrt.insert("filter".into(), v);
    }
    (!pbrt.is_empty()).then(|| Value::Object(pbrt))
}
