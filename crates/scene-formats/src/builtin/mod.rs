//! Built-in procedural scenes, addressed as `builtin:NAME?key=value&…`.
//!
//! Every scene is deterministic for its parameters: the random layout comes from a
//! `rand_pcg::Pcg32` seeded with `seed`. Each has a camera and a default image size chosen so
//! that a 16-spp render is a meaningful test image. Light emission is scaled so the total
//! emitted power (and so the exposure) does not depend on the light count or radius.
//!
//! `roughness` is glTF's perceptual roughness: the GGX α is roughness² (roughness 0.1 → α 0.01).
mod car;
mod cornell;
mod diffuse_quads;
mod emissive_mesh;
mod frosted_panel;
mod glossy_spheres;
mod grid;
mod lamp;
pub mod mesh;
mod rooms;
mod staircase;
mod statue;

use glam::Vec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg32;
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::{Scene, SceneBuilder};
use render_core::suggest::did_you_mean;
use std::f32::consts::PI;

/// What `manylights scenes` prints about one built-in scene.
#[derive(Clone, Debug)]
pub struct BuiltinInfo {
    pub name: &'static str,
    pub description: &'static str,
    /// (key, default value, help) of every parameter.
    pub keys: Vec<(&'static str, &'static str, &'static str)>,
}

/// One parameter of a built-in scene.
struct Key {
    name: &'static str,
    default: &'static str,
    help: &'static str,
}

const fn key(name: &'static str, default: &'static str, help: &'static str) -> Key {
    Key {
        name,
        default,
        help,
    }
}

const SEED_HELP: &str = "seed of the random layout (integer)";
const ROUGHNESS_HELP: &str =
    "glTF roughness of the glossy surfaces, in [0, 1]; GGX alpha = roughness^2";

struct Def {
    name: &'static str,
    description: &'static str,
    keys: &'static [Key],
    build: fn(&Params) -> Result<SceneBuilder, SceneError>,
}

const SCENES: &[Def] = &[
    Def {
        name: "glossy-spheres",
        description: "N small sphere lights spread wide above a glossy ground with glossy and diffuse spheres and boxes",
        keys: &[
            key("lights", "4096", "number of sphere lights"),
            key("radius", "0.01", "radius of each sphere light"),
            key("roughness", "0.1", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: glossy_spheres::build,
    },
    Def {
        name: "diffuse-quads",
        description: "many small one-sided emissive quads facing down over purely diffuse geometry",
        keys: &[
            key(
                "lights",
                "1024",
                "number of emissive quads (2 triangle lights each)",
            ),
            key("seed", "0", SEED_HELP),
        ],
        build: diffuse_quads::build,
    },
    Def {
        name: "emissive-mesh",
        description: "a cloud of small emissive icospheres (triangle lights) over a metal ground with a diffuse sphere and a glossy box",
        keys: &[
            key(
                "lights",
                "1000",
                "number of emissive icospheres (20 x 4^subdivisions triangle lights each)",
            ),
            key("subdivisions", "1", "icosphere subdivisions, 0 to 3"),
            key("radius", "0.02", "radius of each icosphere"),
            key("roughness", "0.2", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: emissive_mesh::build,
    },
    Def {
        name: "frosted-panel",
        description: "a frosted-glass pane (rough dielectric) lit from behind by many small two-sided emissive triangles, a diffuse sphere and a glossy box in front, a few lights above the camera",
        keys: &[
            key(
                "lights",
                "1000",
                "number of emissive triangles (9 in 10 behind the pane)",
            ),
            key("frost", "0.2", "GGX alpha of the pane, in [0.001, 1]"),
            key(
                "ior",
                "1.5",
                "index of refraction of the pane, in [1.01, 3]",
            ),
            key("roughness", "0.3", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: frosted_panel::build,
    },
    Def {
        name: "car",
        description: "glossy car-like body on a glossy ground under a ceiling of small sphere lights and 3 large panels",
        keys: &[
            key(
                "lights",
                "4000",
                "number of ceiling sphere lights (the 3 panels come on top)",
            ),
            key("radius", "0.02", "radius of each sphere light"),
            key("roughness", "0.15", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: car::build,
    },
    Def {
        name: "lamp",
        description: "chandelier of many small bulbs over a glossy table, glossy and diffuse objects and a diffuse room",
        keys: &[
            key("lights", "1200", "number of bulbs (sphere lights)"),
            key("radius", "0.012", "radius of each bulb"),
            key("roughness", "0.12", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: lamp::build,
    },
    Def {
        name: "statue",
        description: "ridged torus-knot statue (diffuse + glossy) on a pedestal, lit by many lights around it",
        keys: &[
            key(
                "lights",
                "2048",
                "number of sphere lights around the statue",
            ),
            key("radius", "0.01", "radius of each sphere light"),
            key("roughness", "0.2", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: statue::build,
    },
    Def {
        name: "cornell",
        description: "modified Cornell box: diffuse walls, two very glossy objects, tiny sphere lights spelling letters on the side walls",
        keys: &[
            key(
                "lights",
                "1494",
                "number of tiny sphere lights on the side walls",
            ),
            key(
                "radius",
                "0.001",
                "radius of each light (the box is 2 units wide)",
            ),
            key("roughness", "0.1", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: cornell::build,
    },
    Def {
        name: "staircase",
        description: "staircase between two walls with small lamps along the steps and a glossy floor",
        keys: &[
            key("lights", "1000", "number of small lamps (sphere lights)"),
            key("radius", "0.015", "radius of each lamp"),
            key("roughness", "0.1", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: staircase::build,
    },
    Def {
        name: "grid",
        description: "N sphere lights on a square grid over a glossy plane with a few objects, for scaling (N from 100 to 1e6)",
        keys: &[
            key(
                "lights",
                "10000",
                "number of lights, 1 to 1e6 (scientific notation allowed)",
            ),
            key(
                "radius",
                "auto",
                "radius of each sphere light; auto = 0.05 x grid spacing (10/ceil(sqrt(N)))",
            ),
            key("roughness", "0.2", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: grid::build,
    },
    Def {
        name: "rooms",
        description: "six rooms off a corridor with a few thousand small lights spread over all of them; the camera looks through a door, so most lights are occluded from most points",
        keys: &[
            key(
                "lights",
                "3000",
                "number of lights (sphere lights and emissive triangles, about 60/40)",
            ),
            key("roughness", "0.15", ROUGHNESS_HELP),
            key("seed", "0", SEED_HELP),
        ],
        build: rooms::build,
    },
];

/// The most lights any built-in accepts.
pub const MAX_LIGHTS: usize = 1_000_000;

/// Every built-in scene with its keys and defaults.
pub fn list_builtins() -> Vec<BuiltinInfo> {
    SCENES
        .iter()
        .map(|d| BuiltinInfo {
            name: d.name,
            description: d.description,
            keys: d.keys.iter().map(|k| (k.name, k.default, k.help)).collect(),
        })
        .collect()
}

/// Builds the scene named by `builtin:NAME?key=value&…` (the `builtin:` prefix is optional).
/// The scene's name is the canonical spec with every key spelled out.
pub fn load_builtin(spec: &str) -> Result<Scene, SceneError> {
    let params = Params::parse(spec)?;
    let def = params.def;
    (def.build)(&params)?.build()
}

/// Parsed parameters of one built-in scene: every key of the scene with its value text.
pub struct Params {
    def: &'static Def,
    values: Vec<(&'static str, String)>,
}

impl Params {
    fn parse(spec: &str) -> Result<Params, SceneError> {
        let rest = spec.strip_prefix("builtin:").unwrap_or(spec);
        let (name, query) = rest.split_once('?').unwrap_or((rest, ""));
        let known = || SCENES.iter().map(|d| d.name).collect::<Vec<_>>().join(", ");
        let def =
            SCENES
                .iter()
                .find(|d| d.name == name)
                .ok_or_else(|| SceneError::UnknownBuiltin {
                    name: name.into(),
                    suggestion: did_you_mean(name, SCENES.iter().map(|d| d.name)),
                    known: known(),
                })?;
        let mut values: Vec<(&'static str, String)> = def
            .keys
            .iter()
            .map(|k| (k.name, k.default.to_string()))
            .collect();
        let mut seen: Vec<&str> = Vec::new();
        for part in query.split('&').filter(|p| !p.is_empty()) {
            let bad = |key: &str, message: String| SceneError::BadBuiltinParam {
                scene: def.name.into(),
                key: key.into(),
                message,
            };
            let (k, v) = part
                .split_once('=')
                .ok_or_else(|| bad(part, "expected key=value".into()))?;
            let valid = || {
                def.keys
                    .iter()
                    .map(|k| k.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            };
            let slot = values
                .iter_mut()
                .find(|(name, _)| *name == k)
                .ok_or_else(|| {
                    let hint = did_you_mean(k, def.keys.iter().map(|k| k.name));
                    bad(k, format!("unknown key{hint} (valid keys: {})", valid()))
                })?;
            if seen.contains(&k) {
                return Err(bad(k, "given twice".into()));
            }
            seen.push(k);
            slot.1 = v.to_string();
        }
        let params = Params { def, values };
        // Check every value now, so a bad one is reported before any work.
        for k in def.keys {
            match k.name {
                "seed" => {
                    params.seed()?;
                }
                "lights" => {
                    params.count("lights", 1, MAX_LIGHTS)?;
                }
                "radius" => {
                    params.radius_or_auto()?;
                }
                "roughness" => {
                    params.number("roughness", 0.0, 1.0)?;
                }
                "subdivisions" => {
                    params.count("subdivisions", 0, 3)?;
                }
                "frost" => {
                    params.number("frost", 1e-3, 1.0)?;
                }
                "ior" => {
                    params.number("ior", 1.01, 3.0)?;
                }
                _ => {}
            }
        }
        Ok(params)
    }

    fn text(&self, key: &str) -> &str {
        &self
            .values
            .iter()
            .find(|(k, _)| *k == key)
            .unwrap_or_else(|| panic!("built-in `{}` reads undeclared key `{key}`", self.def.name))
            .1
    }

    fn bad(&self, key: &str, message: String) -> SceneError {
        SceneError::BadBuiltinParam {
            scene: self.def.name.into(),
            key: key.into(),
            message,
        }
    }

    /// The canonical spec: `builtin:NAME?k=v&…` with every key in declaration order.
    pub fn canonical(&self) -> String {
        let q: Vec<String> = self
            .values
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        format!("builtin:{}?{}", self.def.name, q.join("&"))
    }

    /// An integer in [min, max]; scientific notation (`1e6`) is accepted when integral.
    pub fn count(&self, key: &str, min: usize, max: usize) -> Result<usize, SceneError> {
        let t = self.text(key);
        let n = match t.parse::<usize>() {
            Ok(n) => n,
            Err(_) => match t.parse::<f64>() {
                Ok(f)
                    if f.is_finite() && f >= 0.0 && f.fract() == 0.0 && f <= usize::MAX as f64 =>
                {
                    f as usize
                }
                _ => return Err(self.bad(key, format!("`{t}` is not a whole number"))),
            },
        };
        if n < min || n > max {
            return Err(self.bad(key, format!("{n} is outside [{min}, {max}]")));
        }
        Ok(n)
    }

    /// A finite number in [min, max].
    pub fn number(&self, key: &str, min: f32, max: f32) -> Result<f32, SceneError> {
        let t = self.text(key);
        let x: f32 = t
            .parse()
            .map_err(|_| self.bad(key, format!("`{t}` is not a number")))?;
        if !x.is_finite() || x < min || x > max {
            return Err(self.bad(key, format!("{t} is outside [{min}, {max}]")));
        }
        Ok(x)
    }

    pub fn seed(&self) -> Result<u64, SceneError> {
        let t = self.text("seed");
        t.parse()
            .map_err(|_| self.bad("seed", format!("`{t}` is not a non-negative integer")))
    }

    /// The layout's random number generator.
    pub fn rng(&self) -> Result<Pcg32, SceneError> {
        Ok(Pcg32::seed_from_u64(self.seed()?))
    }

    pub fn lights(&self) -> Result<usize, SceneError> {
        self.count("lights", 1, MAX_LIGHTS)
    }

    pub fn radius(&self) -> Result<f32, SceneError> {
        self.number("radius", 1e-6, 1.0)
    }

    /// The radius, or `None` for `auto` (accepted only where `auto` is the default).
    pub fn radius_or_auto(&self) -> Result<Option<f32>, SceneError> {
        let auto_default = self
            .def
            .keys
            .iter()
            .any(|k| k.name == "radius" && k.default == "auto");
        if auto_default && self.text("radius") == "auto" {
            Ok(None)
        } else {
            self.radius().map(Some)
        }
    }

    pub fn roughness(&self) -> Result<f32, SceneError> {
        self.number("roughness", 0.0, 1.0)
    }

    pub fn builder(&self) -> SceneBuilder {
        SceneBuilder::new(&self.canonical())
    }

    /// The scene's camera, or the error naming this scene where the camera is degenerate.
    pub fn camera(
        &self,
        camera: Result<render_core::camera::Camera, render_core::camera::CameraError>,
    ) -> Result<render_core::camera::Camera, SceneError> {
        camera.map_err(|error| SceneError::BadCamera {
            scene: self.canonical(),
            error,
        })
    }
}

/// Light colours of luminance 1: warm and cool whites and a few tints.
pub fn light_color(rng: &mut Pcg32) -> Vec3 {
    const PALETTE: [[f32; 3]; 8] = [
        [1.0, 0.85, 0.65],
        [1.0, 0.95, 0.9],
        [0.8, 0.9, 1.0],
        [1.0, 0.6, 0.35],
        [0.55, 0.75, 1.0],
        [1.0, 0.5, 0.6],
        [0.6, 1.0, 0.6],
        [1.0, 1.0, 1.0],
    ];
    let c = Vec3::from(PALETTE[(rng.random::<u32>() % PALETTE.len() as u32) as usize]);
    c / render_core::colour::luminance(c)
}

/// Radiance (luminance) of each of `n` sphere lights of radius `r` so that together they emit
/// `total_power` (the unit of `Light::power`: π·L·4πr² per sphere).
pub fn sphere_radiance(total_power: f32, n: usize, r: f32) -> f32 {
    total_power / (n as f32 * 4.0 * PI * PI * r * r)
}

/// Radiance (luminance) of each of `n` one-sided emitters of area `area` emitting
/// `total_power` together (π·L·A each).
pub fn area_radiance(total_power: f32, n: usize, area: f32) -> f32 {
    total_power / (n as f32 * PI * area)
}

/// A black, one-sided (unless `double_sided`) emitter material.
pub fn emitter(name: &str, radiance: Vec3, double_sided: bool) -> Material {
    Material {
        emission: radiance,
        double_sided,
        ..Material::diffuse(name, Vec3::splat(0.02))
    }
}

/// A uniform number in [a, b).
pub fn uniform(rng: &mut Pcg32, a: f32, b: f32) -> f32 {
    a + (b - a) * rng.random::<f32>()
}

/// A uniform index in [0, n).
pub fn pick(rng: &mut Pcg32, n: usize) -> usize {
    rng.random_range(0..n as u32) as usize
}

#[cfg(test)]
mod tests;
