//! The pbrt scene-description interpreter: the [`Parser`] (its state between directives), its
//! main loop and the directive dispatch. Each group of directives is a module of its own:
//!
//! * `input`: the include stack, tokens, arguments and parameter lists, messages;
//! * `transform_directives`: the graphics state's blocks, transforms, coordinate systems;
//! * `material_directives`: textures and materials (named or not);
//! * `shape_directives`: shapes and object instances;
//! * `light_directives`: light sources and area lights;
//! * `camera_directives`: the camera and the film;
//! * `option_directives`: sampler, pixel filter, integrator and the other settings we warn
//!   about;
//! * `records`: the plain data the parser keeps (graphics state, blocks, instances).
//!
//! Every directive maps onto the [`SceneBuilder`], which validates what it is given.
mod camera_directives;
mod input;
mod light_directives;
mod material_directives;
mod option_directives;
mod records;
mod shape_directives;
mod transform_directives;

use super::materials::{self, TextureValue};
use super::tokenizer::Token;
use glam::{DMat4, Mat4};
use records::{Block, CameraSpec, Instanced, Source, State};
use render_core::error::SceneError;
use render_core::material::Material;
use render_core::scene::SceneBuilder;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// What a pbrt file contributed, besides the geometry.
#[derive(Clone, Debug, Default)]
pub struct PbrtReport {
    pub shapes: usize,
    pub triangles: usize,
    pub sphere_lights: usize,
    pub point_lights: usize,
    pub spot_lights: usize,
    pub distant_lights: usize,
    pub instances: usize,
    /// `file:line: what`, one per distinct message (later repeats are counted).
    pub warnings: Vec<String>,
}

/// Reads one pbrt file (and its includes) into a [`SceneBuilder`].
pub struct Parser<'b> {
    builder: &'b mut SceneBuilder,
    root: DMat4,
    base_dir: PathBuf,
    sources: Vec<Source>,
    state: State,
    stack: Vec<(State, Block, String)>,
    named_coords: HashMap<String, DMat4>,
    materials: Vec<Material>,
    named_materials: HashMap<String, Option<usize>>,
    /// Builder material of (material, area light identity).
    built: HashMap<(usize, usize), u32>,
    textures: HashMap<String, TextureValue>,
    objects: HashMap<String, Vec<Instanced>>,
    object: Option<(String, Vec<Instanced>)>,
    camera: Option<CameraSpec>,
    film: (u32, u32),
    end_time_only: bool,
    warnings: Vec<(String, String, usize)>,
    pub report: PbrtReport,
}

/// The f32 transform the builder takes (the parser composes in f64).
/// The f32 transform the builder takes (the parser composes in f64).
fn to_f32(m: DMat4) -> Mat4 {
    m.as_mat4()
}

impl<'b> Parser<'b> {
    /// A parser of the file at `path`, adding to `builder` under the transform `root`.
    pub fn new(builder: &'b mut SceneBuilder, path: &Path, root: Mat4) -> Result<Self, SceneError> {
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut named_coords = HashMap::new();
        named_coords.insert("world".to_string(), DMat4::IDENTITY);
        let mut p = Parser {
            builder,
            root: root.as_dmat4(),
            base_dir,
            sources: Vec::new(),
            state: State {
                ctm: DMat4::IDENTITY,
                reverse: false,
                material: Some(0),
                area_light: None,
            },
            stack: Vec::new(),
            named_coords,
            materials: vec![materials::default_material()],
            named_materials: HashMap::new(),
            built: HashMap::new(),
            textures: HashMap::new(),
            objects: HashMap::new(),
            object: None,
            camera: None,
            film: (1280, 720),
            end_time_only: false,
            warnings: Vec::new(),
            report: PbrtReport::default(),
        };
        p.open(path, None)?;
        Ok(p)
    }

    /// Reads every directive, then makes the camera; returns what was read and the warnings.
    pub fn run(mut self) -> Result<PbrtReport, SceneError> {
        loop {
            let next = self.next_in_file()?;
            let Some((token, line)) = next else {
                if self.sources.len() == 1 {
                    break;
                }
                self.sources.pop();
                continue;
            };
            match token {
                Token::Word(w) => self.directive(&w, line)?,
                t => {
                    return Err(self.err(
                        line,
                        format!("expected a directive, found {}", t.describe()),
                    ));
                }
            }
        }
        let end = self.eof_line();
        if let Some((_, _, at)) = self.stack.last() {
            let at = at.clone();
            self.warn(end, format!("{at}: block opened here is never closed"));
        }
        self.finish_camera()?;
        let mut report = std::mem::take(&mut self.report);
        report.warnings = self
            .warnings
            .iter()
            .map(|(m, at, n)| {
                if *n > 1 {
                    format!("{at}: {m} (and {} more times)", n - 1)
                } else {
                    format!("{at}: {m}")
                }
            })
            .collect();
        Ok(report)
    }

    /// One directive, by name: each group is handled in its own module (see above).
    fn directive(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        match d {
            "Include" | "Import" => self.include(d, line)?,
            // the graphics state and transforms
            "WorldBegin" => self.world_begin(),
            "WorldEnd" => {}
            "AttributeBegin" | "TransformBegin" => self.begin_block(d, line),
            "AttributeEnd" | "TransformEnd" => self.end_block(d, line)?,
            "Identity" | "Translate" | "Scale" | "Rotate" | "LookAt" | "Transform"
            | "ConcatTransform" => self.transform(d, line)?,
            "CoordinateSystem" | "CoordSysTransform" => self.coordinate_system(d, line)?,
            "ActiveTransform" => self.active_transform(line)?,
            "TransformTimes" => self.transform_times(d, line)?,
            "ReverseOrientation" => self.reverse_orientation(),
            // camera, film and rendering options
            "Camera" => self.camera_directive(line)?,
            "Film" => self.film_directive(line)?,
            "Sampler" => self.sampler_directive(line)?,
            "PixelFilter" => self.pixel_filter_directive(line)?,
            "Integrator" | "Accelerator" | "SurfaceIntegrator" | "VolumeIntegrator"
            | "Renderer" => self.renderer_setting(d, line)?,
            "ColorSpace" => self.color_space(line)?,
            "Option" => self.option_directive(line)?,
            "MakeNamedMedium" | "MediumInterface" => self.medium_directive(d, line)?,
            "Attribute" => self.attribute_directive(line)?,
            // materials and textures
            "Texture" => self.texture_directive(line)?,
            "Material" => self.material_directive(line)?,
            "MakeNamedMaterial" => self.make_named_material(line)?,
            "NamedMaterial" => self.named_material(line)?,
            // lights
            "LightSource" => self.light_directive(line)?,
            "AreaLightSource" => self.area_light_directive(line)?,
            // shapes and instances
            "Shape" => self.shape_directive(line)?,
            "ObjectBegin" => self.object_begin(line)?,
            "ObjectEnd" => self.object_end(line)?,
            "ObjectInstance" => self.object_instance(line)?,
            other => return Err(self.err(line, format!("unknown directive `{other}`"))),
        }
        Ok(())
    }
}
