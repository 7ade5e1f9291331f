//! Cached references: `references/<identity hash>/` holds `ref.exr` (the average of two
//! independent halves), `mask.png` (white where the camera sees a light in either half),
//! `ref.png` (preview), `half-a.exr`/`half-b.exr` (not committed) and `manifest.json`, written
//! last, so a directory without a manifest is an interrupted render.
use super::manylights::{Failure, Manylights};
use super::plan::{hex_hash, slug};
use super::progress::say;
use glam::Vec3;
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use render_core::metrics::error_metrics;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Bump to render every cached reference again by hand. Changes of the loaded scene (any file
/// a loader reads, or how it understands materials) and of the reference strategy's
/// parameters invalidate references on their own, through [`Validity`].
pub const REFERENCE_EPOCH: u32 = 1;

/// Relative and absolute squared error over a set of pixels.
#[derive(Clone, Copy, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Metric {
    pub rel_mse: f64,
    pub mse: f64,
    pub pixels: usize,
}

impl From<render_core::metrics::ErrorMetrics> for Metric {
    fn from(m: render_core::metrics::ErrorMetrics) -> Self {
        Metric {
            rel_mse: m.rel_mse,
            mse: m.mse,
            pixels: m.pixels,
        }
    }
}

/// What a reference is: its directory is the hash of this.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Identity {
    pub scene: String,
    pub camera: Option<String>,
    pub strategy: String,
    pub args: Vec<String>,
    pub spp: u32,
    pub seed: u64,
    pub width: u32,
    pub height: u32,
}

impl Identity {
    pub fn dir_name(&self) -> String {
        let scene = super::config::label_from_spec(&self.scene);
        let short: String = slug(&scene).chars().take(40).collect();
        format!(
            "{short}-{}",
            hex_hash(serde_json::to_string(self).unwrap().as_bytes())
        )
    }
}

/// Beyond the identity, what must still hold for a cached reference to be valid: the scene as
/// loaded and the reference strategy as resolved, as the binary reports them. The code of the
/// strategies is not part of it: any unbiased strategy converges to the same image.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Validity {
    /// `manylights info --json`'s `scene_hash` (geometry, materials as understood, lights,
    /// cameras: every file the loader read).
    pub scene_hash: String,
    /// `manylights strategy --json` of the reference strategy: its parameters, defaults
    /// included, and the sampler.
    pub strategy: serde_json::Value,
    pub epoch: u32,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Manifest {
    pub identity: Identity,
    pub validity: Validity,
    /// Recorded, not checked: references stay valid across commits (see references/README.md).
    pub git_commit: Option<String>,
    pub created_unix: u64,
    /// Wall seconds of the two halves together.
    pub wall_seconds: f64,
    /// relMSE between the two halves; the average's own relMSE is about a quarter of it.
    pub noise_all: Metric,
    pub noise_unlit: Metric,
    pub unlit_fraction: f64,
}

impl Manifest {
    /// Estimated relMSE of the reference itself (unlit pixels): half-vs-half / 4.
    pub fn own_rel_mse(&self) -> f64 {
        self.noise_unlit.rel_mse / 4.0
    }
    /// Stable id of this exact reference (cells measured against another are stale).
    pub fn content_id(&self) -> String {
        hex_hash(
            serde_json::to_string(&(&self.identity, &self.validity))
                .unwrap()
                .as_bytes(),
        )
    }
}

/// A valid cached reference, loaded.
pub struct Reference {
    pub dir: PathBuf,
    pub manifest: Manifest,
    pub pixels: Vec<Vec3>,
    /// true where the camera sees no light.
    pub unlit: Vec<bool>,
    /// Rendered by this run (not reused from the cache).
    pub rendered: bool,
}

/// Why the cached reference in `dir` cannot be used (`Ok` = valid).
pub fn check(dir: &Path, identity: &Identity, validity: &Validity) -> Result<Manifest, String> {
    let path = dir.join("manifest.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|_| "no manifest (never rendered or interrupted)".to_string())?;
    let m: Manifest =
        serde_json::from_str(&text).map_err(|e| format!("unreadable manifest: {e}"))?;
    if &m.identity != identity {
        return Err("manifest is for another reference".into());
    }
    if m.validity.scene_hash != validity.scene_hash {
        return Err("the loaded scene changed".into());
    }
    if m.validity.strategy != validity.strategy {
        return Err("the reference strategy's resolved parameters changed".into());
    }
    if m.validity.epoch != validity.epoch {
        return Err("reference epoch bumped".into());
    }
    for f in ["ref.exr", "mask.png"] {
        if !dir.join(f).is_file() {
            return Err(format!("{f} is missing"));
        }
    }
    Ok(m)
}

pub fn load(dir: &Path, manifest: Manifest) -> Result<Reference, String> {
    let (w, h, pixels) = render_core::output::read_exr(&dir.join("ref.exr"))?;
    if (w, h) != (manifest.identity.width, manifest.identity.height) {
        return Err(format!("ref.exr is {w}x{h}, not the manifest's size"));
    }
    let unlit = render_core::output::read_mask_png(&dir.join("mask.png"), w, h)?;
    Ok(Reference {
        dir: dir.to_path_buf(),
        manifest,
        pixels,
        unlit,
        rendered: false,
    })
}

pub struct Ensure<'a> {
    pub ml: &'a Manylights,
    pub refs_dir: &'a Path,
    pub identity: Identity,
    pub validity: Validity,
    pub threads: Option<usize>,
    pub force: bool,
}

impl Ensure<'_> {
    /// The valid cached reference, or renders it (two halves) and caches it.
    pub fn run(self, multi: &MultiProgress) -> Result<Reference, Failure> {
        let dir = self.refs_dir.join(self.identity.dir_name());
        if !self.force
            && let Ok(m) = check(&dir, &self.identity, &self.validity)
        {
            return load(&dir, m).map_err(Failure::Error);
        }
        let why = if self.force {
            "--refresh-references".to_string()
        } else {
            check(&dir, &self.identity, &self.validity).unwrap_err()
        };
        say(
            multi,
            format!(
                "reference {} ({why}): rendering {} × {} spp with {}",
                dir.display(),
                2,
                self.identity.spp / 2,
                self.identity.strategy
            ),
        )
        .ok();
        std::fs::create_dir_all(&dir)
            .map_err(|e| Failure::Error(format!("cannot create {}: {e}", dir.display())))?;
        let _ = std::fs::remove_file(dir.join("manifest.json"));
        let id = &self.identity;
        let mut halves = Vec::new();
        let mut wall = 0.0;
        let mut commit = None;
        for (k, name) in ["half-a", "half-b"].iter().enumerate() {
            let out = dir.join(format!("{name}.exr"));
            let mut args = vec![
                id.scene.clone(),
                "--strategy".into(),
                id.strategy.clone(),
                "--spp".into(),
                (id.spp / 2).to_string(),
                "--seed".into(),
                (id.seed + k as u64).to_string(),
                "--width".into(),
                id.width.to_string(),
                "--height".into(),
                id.height.to_string(),
                "--aux".into(),
            ];
            if let Some(c) = &id.camera {
                args.extend(["--camera".into(), c.clone()]);
            }
            if let Some(t) = self.threads {
                args.extend(["--threads".into(), t.to_string()]);
            }
            args.extend(id.args.iter().cloned());
            let bar = multi.add(ProgressBar::new_spinner());
            bar.set_style(
                ProgressStyle::with_template("{spinner} [{elapsed_precise}] {msg}")
                    .unwrap_or(ProgressStyle::default_spinner()),
            );
            bar.set_message(format!(
                "reference {} {name} ({} spp)",
                super::config::label_from_spec(&id.scene),
                id.spp / 2
            ));
            let json = self.ml.render(&args, &out, &bar, None);
            bar.finish_and_clear();
            let json = json?;
            if json["scene_hash"].as_str() != Some(self.validity.scene_hash.as_str()) {
                return Err(Failure::Error(format!(
                    "{name} rendered scene {}, not the one planned ({}): did a scene file change during the run?",
                    json["scene_hash"], self.validity.scene_hash
                )));
            }
            wall += json["wall_seconds"].as_f64().unwrap_or(0.0);
            commit = json["git_commit"].as_str().map(str::to_string);
            let (w, h, px) = render_core::output::read_exr(&out).map_err(Failure::Error)?;
            let unlit =
                render_core::output::read_mask_png(&dir.join(format!("{name}.mask.png")), w, h)
                    .map_err(Failure::Error)?;
            halves.push((px, unlit));
        }
        let (a, ua) = &halves[0];
        let (b, ub) = &halves[1];
        let avg: Vec<Vec3> = a.iter().zip(b).map(|(x, y)| (*x + *y) * 0.5).collect();
        let unlit: Vec<bool> = ua.iter().zip(ub).map(|(x, y)| *x && *y).collect();
        let noise_all = error_metrics(a, b, None).into();
        let noise_unlit = error_metrics(a, b, Some(&unlit)).into();
        let (w, h) = (id.width, id.height);
        let err = |e: String| Failure::Error(e);
        render_core::output::write_exr(&dir.join("ref.exr"), w, h, &avg).map_err(err)?;
        let lit: Vec<f32> = unlit.iter().map(|&u| if u { 0.0 } else { 1.0 }).collect();
        render_core::output::write_mask_png(&dir.join("mask.png"), w, h, &lit).map_err(err)?;
        let scale = super::compositing::auto_exposure(&avg, &unlit);
        let rgb = super::compositing::tonemap(&avg, scale);
        render_core::output::write_png_rgb8(&dir.join("ref.png"), w, h, &rgb).map_err(err)?;
        for name in ["half-a", "half-b"] {
            let _ = std::fs::remove_file(dir.join(format!("{name}.mask.png")));
        }
        let manifest = Manifest {
            identity: self.identity.clone(),
            validity: self.validity.clone(),
            git_commit: commit,
            created_unix: std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_secs())
                .unwrap_or(0),
            wall_seconds: wall,
            noise_all,
            noise_unlit,
            unlit_fraction: unlit.iter().filter(|&&u| u).count() as f64 / unlit.len().max(1) as f64,
        };
        render_core::output::write_json(
            &dir.join("manifest.json"),
            &serde_json::to_value(&manifest).unwrap(),
        )
        .map_err(err)?;
        say(multi, format!(
                "reference {}: {:.1} s, half-vs-half relMSE {:.3e} (unlit pixels), its own ≈ {:.3e}",
                dir.display(),
                wall,
                manifest.noise_unlit.rel_mse,
                manifest.own_rel_mse()
            ))
            .ok();
        Ok(Reference {
            dir,
            manifest,
            pixels: avg,
            unlit,
            rendered: true,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn identity() -> Identity {
        Identity {
            scene: "builtin:glossy-spheres?lights=64".into(),
            camera: None,
            strategy: "power+bsdf".into(),
            args: vec![],
            spp: 64,
            seed: 7,
            width: 4,
            height: 2,
        }
    }

    fn validity() -> Validity {
        Validity {
            scene_hash: "abc".into(),
            strategy: serde_json::json!({ "strategy": "power+bsdf", "parameters": {} }),
            epoch: REFERENCE_EPOCH,
        }
    }

    fn write_valid(dir: &Path) -> Manifest {
        std::fs::create_dir_all(dir).unwrap();
        let px = vec![Vec3::splat(0.5); 8];
        render_core::output::write_exr(&dir.join("ref.exr"), 4, 2, &px).unwrap();
        render_core::output::write_mask_png(&dir.join("mask.png"), 4, 2, &[0.0; 8]).unwrap();
        let m = Manifest {
            identity: identity(),
            validity: validity(),
            git_commit: Some("deadbeef".into()),
            created_unix: 0,
            wall_seconds: 1.0,
            noise_all: Metric::default(),
            noise_unlit: Metric {
                rel_mse: 0.04,
                mse: 0.0,
                pixels: 8,
            },
            unlit_fraction: 1.0,
        };
        render_core::output::write_json(
            &dir.join("manifest.json"),
            &serde_json::to_value(&m).unwrap(),
        )
        .unwrap();
        m
    }

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("xtask-ref-test-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn manifest_validity() {
        let dir = tmp("validity");
        assert!(
            check(&dir, &identity(), &validity())
                .unwrap_err()
                .contains("no manifest")
        );
        let m = write_valid(&dir);
        assert_eq!(check(&dir, &identity(), &validity()).unwrap(), m);
        assert!((m.own_rel_mse() - 0.01).abs() < 1e-12);
        let r = load(&dir, m.clone()).unwrap();
        assert_eq!(r.unlit, vec![true; 8]);

        let mut other = identity();
        other.spp = 128;
        assert!(check(&dir, &other, &validity()).is_err());
        let mut v = validity();
        v.scene_hash = "changed".into();
        assert!(
            check(&dir, &identity(), &v)
                .unwrap_err()
                .contains("scene changed")
        );
        let mut v = validity();
        v.strategy["parameters"] = serde_json::json!({ "tau": 0.5 });
        assert!(
            check(&dir, &identity(), &v)
                .unwrap_err()
                .contains("resolved parameters")
        );
        let mut v = validity();
        v.epoch += 1;
        assert!(check(&dir, &identity(), &v).is_err());
        // a different commit is recorded but does not invalidate
        std::fs::remove_file(dir.join("mask.png")).unwrap();
        assert!(
            check(&dir, &identity(), &validity())
                .unwrap_err()
                .contains("mask.png")
        );
        std::fs::write(dir.join("manifest.json"), "{").unwrap();
        assert!(
            check(&dir, &identity(), &validity())
                .unwrap_err()
                .contains("unreadable")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn identity_names_are_stable_and_distinct() {
        let a = identity().dir_name();
        assert_eq!(a, identity().dir_name());
        assert!(a.starts_with("glossy-spheres-lights=64-"));
        let mut b = identity();
        b.seed = 8;
        assert_ne!(a, b.dir_name());
    }
}
