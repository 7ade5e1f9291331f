//! The pbrt scene-description interpreter: the include stack, the graphics state (transform,
//! material, area light, orientation) with its `AttributeBegin`/`End` stack, named materials,
//! textures, coordinate systems and object instances, and every directive's mapping onto the
//! [`SceneBuilder`] (which validates what it is given).
use super::materials::{self, Context, TextureValue};
use super::params::{Param, ParamList, Values};
use super::shapes::{self, MeshData};
use super::tokenizer::{Token, Tokenizer};
use glam::{DMat4, DVec3, Mat4, Vec3};
use render_core::camera::Camera;
use render_core::error::SceneError;
use render_core::light::SpotCone;
use render_core::material::Material;
use render_core::scene::SceneBuilder;
use std::collections::HashMap;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::Arc;

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

struct Source {
    tokens: Tokenizer<BufReader<File>>,
    /// As named (for messages) and canonical (for include cycles).
    shown: String,
    canonical: PathBuf,
}

#[derive(Clone)]
struct AreaLight {
    radiance: Vec3,
    two_sided: bool,
}

#[derive(Clone)]
struct State {
    ctm: DMat4,
    reverse: bool,
    /// Index into `Parser::materials`; `None`: `interface` (no surface).
    material: Option<usize>,
    area_light: Option<Arc<AreaLight>>,
}

/// A shape recorded inside `ObjectBegin`/`ObjectEnd`, added once per `ObjectInstance`.
struct Instanced {
    mesh: Arc<MeshData>,
    ctm: DMat4,
    material: u32,
    name: String,
}

enum Block {
    Attribute,
    Transform,
    Object,
}

/// Camera directive as read; made into a [`Camera`] at the end, once the film is known.
struct CameraSpec {
    camera_from_world: DMat4,
    fov_degrees: f64,
    line: String,
}

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

fn to_f32(m: DMat4) -> Mat4 {
    m.as_mat4()
}

impl<'b> Parser<'b> {
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

    // ---- errors, warnings and positions -------------------------------------------------

    fn here(&self, line: usize) -> String {
        let file = self.sources.last().map_or("?", |s| s.shown.as_str());
        format!("{file}:{line}")
    }

    fn err(&self, line: usize, message: impl Into<String>) -> SceneError {
        SceneError::Pbrt {
            path: self
                .sources
                .last()
                .map_or_else(|| "?".into(), |s| s.shown.clone()),
            line,
            message: message.into(),
        }
    }

    fn warn(&mut self, line: usize, message: impl Into<String>) {
        let message = message.into();
        let at = self.here(line);
        match self.warnings.iter_mut().find(|w| w.0 == message) {
            Some(w) => w.2 += 1,
            None => self.warnings.push((message, at, 1)),
        }
    }

    // ---- sources -----------------------------------------------------------------------

    /// Opens a file (relative paths: to the main file's directory, as pbrt resolves them).
    fn open(&mut self, name: &Path, line: Option<usize>) -> Result<(), SceneError> {
        let path = if name.is_absolute() || self.sources.is_empty() {
            name.to_path_buf()
        } else {
            self.base_dir.join(name)
        };
        let fail = |this: &Self, message: String| match line {
            Some(l) => this.err(l, message),
            None => SceneError::Io {
                path: path.display().to_string(),
                message: message.clone(),
            },
        };
        if path.extension().is_some_and(|e| e == "gz") {
            return Err(fail(
                self,
                format!(
                    "{}: gzip-compressed files are not supported (gunzip it first)",
                    path.display()
                ),
            ));
        }
        let file = File::open(&path)
            .map_err(|e| fail(self, format!("cannot open {}: {e}", path.display())))?;
        let canonical = path.canonicalize().unwrap_or_else(|_| path.clone());
        if let Some(k) = self.sources.iter().position(|s| s.canonical == canonical) {
            let chain: Vec<&str> = self.sources[k..].iter().map(|s| s.shown.as_str()).collect();
            return Err(fail(
                self,
                format!("Include cycle: {} → {}", chain.join(" → "), path.display()),
            ));
        }
        self.sources.push(Source {
            tokens: Tokenizer::new(BufReader::with_capacity(1 << 18, file)),
            shown: path.display().to_string(),
            canonical,
        });
        Ok(())
    }

    fn lex_err(&self, e: super::tokenizer::LexError) -> SceneError {
        self.err(e.line, e.message)
    }

    /// The next token of the current file (a directive's arguments never span files).
    fn next_in_file(&mut self) -> Result<Option<(Token, usize)>, SceneError> {
        let src = self.sources.last_mut().expect("a source is open");
        src.tokens.next().map_err(|e| {
            let e2 = super::tokenizer::LexError {
                line: e.line,
                message: e.message,
            };
            self.lex_err(e2)
        })
    }

    fn peek_in_file(&mut self) -> Result<Option<Token>, SceneError> {
        let src = self.sources.last_mut().expect("a source is open");
        match src.tokens.peek() {
            Ok(t) => Ok(t.map(|t| t.0.clone())),
            Err(e) => Err(self.lex_err(e)),
        }
    }

    fn peek_is_str(&mut self) -> Result<bool, SceneError> {
        let src = self.sources.last_mut().expect("a source is open");
        match src.tokens.peek() {
            Ok(t) => Ok(matches!(t, Some((Token::Str(_), _)))),
            Err(e) => Err(self.lex_err(e)),
        }
    }

    fn eof_line(&self) -> usize {
        self.sources.last().map_or(0, |s| s.tokens.line())
    }

    fn string_arg(&mut self, directive: &str, line: usize) -> Result<String, SceneError> {
        match self.next_in_file()? {
            Some((Token::Str(s), _)) => Ok(s),
            Some((t, l)) => Err(self.err(
                l,
                format!(
                    "{directive} expects a quoted string, found {}",
                    t.describe()
                ),
            )),
            None => Err(self.err(line, format!("{directive}: unexpected end of file"))),
        }
    }

    /// `n` numbers, bare or in one pair of brackets.
    fn numbers(&mut self, directive: &str, n: usize, line: usize) -> Result<Vec<f64>, SceneError> {
        let bracketed = matches!(self.peek_in_file()?, Some(Token::Open));
        if bracketed {
            self.next_in_file()?;
        }
        let mut v = Vec::with_capacity(n);
        while v.len() < n {
            match self.next_in_file()? {
                Some((Token::Num(x), _)) => v.push(x),
                Some((t, l)) => {
                    return Err(self.err(
                        l,
                        format!("{directive} expects {n} numbers, found {}", t.describe()),
                    ));
                }
                None => return Err(self.err(line, format!("{directive}: unexpected end of file"))),
            }
        }
        if bracketed {
            match self.next_in_file()? {
                Some((Token::Close, _)) => {}
                Some((t, l)) => {
                    return Err(self.err(
                        l,
                        format!(
                            "{directive} expects {n} numbers then `]`, found {}",
                            t.describe()
                        ),
                    ));
                }
                None => return Err(self.err(line, format!("{directive}: unexpected end of file"))),
            }
        }
        Ok(v)
    }

    /// A parameter list: `"type name" value` or `"type name" [ values ]`, repeated.
    fn params(&mut self) -> Result<ParamList, SceneError> {
        let mut list = ParamList::default();
        while self.peek_is_str()? {
            let Some((Token::Str(decl), line)) = self.next_in_file()? else {
                unreachable!()
            };
            let values = match self.next_in_file()? {
                Some((Token::Open, _)) => {
                    let mut nums = Vec::new();
                    let mut strs = Vec::new();
                    let mut bools = Vec::new();
                    loop {
                        match self.next_in_file()? {
                            Some((Token::Close, _)) => break,
                            Some((Token::Num(x), _)) => nums.push(x),
                            Some((Token::Str(s), _)) => strs.push(s),
                            Some((Token::Word(w), _)) if w == "true" || w == "false" => {
                                bools.push(w == "true")
                            }
                            Some((t, l)) => {
                                return Err(self.err(
                                    l,
                                    format!(
                                        "parameter \"{decl}\": unexpected {} in its values",
                                        t.describe()
                                    ),
                                ));
                            }
                            None => {
                                return Err(self.err(line, format!("parameter \"{decl}\": `[` without `]` before the end of the file")));
                            }
                        }
                    }
                    match (nums.is_empty(), strs.is_empty(), bools.is_empty()) {
                        (_, true, true) => Values::Nums(nums),
                        (true, false, true) => Values::Strs(strs),
                        (true, true, false) => Values::Bools(bools),
                        _ => {
                            return Err(self.err(
                                line,
                                format!("parameter \"{decl}\" mixes numbers, strings and booleans"),
                            ));
                        }
                    }
                }
                Some((Token::Num(x), _)) => Values::Nums(vec![x]),
                Some((Token::Str(s), _)) => Values::Strs(vec![s]),
                Some((Token::Word(w), _)) if w == "true" || w == "false" => {
                    Values::Bools(vec![w == "true"])
                }
                Some((t, l)) => {
                    return Err(self.err(
                        l,
                        format!("parameter \"{decl}\" has no value (found {})", t.describe()),
                    ));
                }
                None => {
                    return Err(self.err(
                        line,
                        format!("parameter \"{decl}\" has no value before the end of the file"),
                    ));
                }
            };
            let p = Param::new(&decl, values, line).map_err(|m| self.err(line, m))?;
            if list.has(&p.name) {
                self.warn(
                    line,
                    format!("parameter `{}` given twice: the first is used", p.name),
                );
                continue;
            }
            list.params.push(p);
        }
        Ok(list)
    }

    /// Warns about the parameters a directive did not use.
    fn unused(&mut self, what: &str, params: &ParamList, except: &[&str]) {
        let unused: Vec<(String, usize)> = params
            .unused()
            .filter(|p| !except.contains(&p.name.as_str()))
            .map(|p| (format!("{} {}", p.ty, p.name), p.line))
            .collect();
        for (name, line) in unused {
            self.warn(
                line,
                format!("{what}: parameter \"{name}\" is not supported (ignored)"),
            );
        }
    }

    // ---- the main loop ------------------------------------------------------------------

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

    fn directive(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        match d {
            "Include" | "Import" => {
                let name = self.string_arg(d, line)?;
                self.open(Path::new(&name), Some(line))?;
            }
            "WorldBegin" => {
                self.state.ctm = DMat4::IDENTITY;
                self.named_coords.insert("world".into(), DMat4::IDENTITY);
            }
            "WorldEnd" => {}
            "AttributeBegin" | "TransformBegin" => {
                let kind = if d == "AttributeBegin" {
                    Block::Attribute
                } else {
                    Block::Transform
                };
                let at = self.here(line);
                self.stack.push((self.state.clone(), kind, at));
            }
            "AttributeEnd" | "TransformEnd" => match self.stack.pop() {
                Some((saved, Block::Attribute, _)) if d == "AttributeEnd" => self.state = saved,
                Some((saved, Block::Transform, _)) if d == "TransformEnd" => {
                    self.state.ctm = saved.ctm
                }
                Some((_, _, at)) => {
                    return Err(
                        self.err(line, format!("{d} does not match the block opened at {at}"))
                    );
                }
                None => return Err(self.err(line, format!("{d} without a matching begin"))),
            },
            "Identity" => self.state.ctm = DMat4::IDENTITY,
            "Translate" => {
                let v = self.numbers(d, 3, line)?;
                self.concat(DMat4::from_translation(DVec3::new(v[0], v[1], v[2])), line);
            }
            "Scale" => {
                let v = self.numbers(d, 3, line)?;
                self.concat(DMat4::from_scale(DVec3::new(v[0], v[1], v[2])), line);
            }
            "Rotate" => {
                let v = self.numbers(d, 4, line)?;
                let axis = DVec3::new(v[1], v[2], v[3]);
                if axis.length_squared() == 0.0 {
                    return Err(self.err(line, "Rotate about a zero axis"));
                }
                self.concat(
                    DMat4::from_axis_angle(axis.normalize(), v[0].to_radians()),
                    line,
                );
            }
            "LookAt" => {
                let v = self.numbers(d, 9, line)?;
                let m = look_at(
                    DVec3::new(v[0], v[1], v[2]),
                    DVec3::new(v[3], v[4], v[5]),
                    DVec3::new(v[6], v[7], v[8]),
                )
                .map_err(|m| self.err(line, m))?;
                self.concat(m, line);
            }
            "Transform" | "ConcatTransform" => {
                let v = self.numbers(d, 16, line)?;
                let m = DMat4::from_cols_slice(&v);
                if d == "Transform" {
                    if !self.end_time_only {
                        self.state.ctm = m;
                    }
                } else {
                    self.concat(m, line);
                }
            }
            "CoordinateSystem" => {
                let n = self.string_arg(d, line)?;
                self.named_coords.insert(n, self.state.ctm);
            }
            "CoordSysTransform" => {
                let n = self.string_arg(d, line)?;
                match self.named_coords.get(&n) {
                    Some(m) => self.state.ctm = *m,
                    None => self.warn(
                        line,
                        format!("CoordSysTransform: no coordinate system named `{n}` (ignored)"),
                    ),
                }
            }
            "ActiveTransform" => {
                let which = match self.next_in_file()? {
                    Some((Token::Word(w), _)) => w,
                    _ => {
                        return Err(
                            self.err(line, "ActiveTransform expects StartTime, EndTime or All")
                        );
                    }
                };
                self.end_time_only = which == "EndTime";
                if which != "StartTime" {
                    self.warn(line, "ActiveTransform: motion blur is not supported; only start-time transforms are used");
                }
            }
            "TransformTimes" => {
                self.numbers(d, 2, line)?;
                self.warn(
                    line,
                    "TransformTimes: motion blur is not supported (ignored)",
                );
            }
            "ReverseOrientation" => self.state.reverse = !self.state.reverse,
            "Camera" => self.camera_directive(line)?,
            "Film" => {
                let _ty = self.string_arg(d, line)?;
                let p = self.params()?;
                let w = p.int("xresolution", 1280).map_err(|m| self.err(line, m))?;
                let h = p.int("yresolution", 720).map_err(|m| self.err(line, m))?;
                if !(1..=65536).contains(&w) || !(1..=65536).contains(&h) {
                    return Err(
                        self.err(line, format!("Film resolution {w} × {h} is out of range"))
                    );
                }
                self.film = (w as u32, h as u32);
                self.unused("Film", &p, &["filename"]);
            }
            "Sampler" | "Integrator" | "PixelFilter" | "Accelerator" | "SurfaceIntegrator"
            | "VolumeIntegrator" | "Renderer" => {
                let ty = self.string_arg(d, line)?;
                self.params()?;
                let what = match d {
                    "Sampler" => "the strategy, spp and seed come from the command line",
                    "Integrator" => {
                        "only direct lighting is computed, by the strategy the command line names"
                    }
                    "PixelFilter" => "a one-pixel box filter is used",
                    _ => "ignored",
                };
                self.warn(line, format!("{d} \"{ty}\": {what}"));
            }
            "ColorSpace" => {
                let cs = self.string_arg(d, line)?;
                self.warn(
                    line,
                    format!("ColorSpace \"{cs}\": colours are read as linear RGB as given"),
                );
            }
            "Option" => {
                let p = self.params()?;
                for q in &p.params {
                    p.touch(&q.name);
                }
                self.warn(line, "Option: rendering options are ignored");
            }
            "MakeNamedMedium" => {
                let name = self.string_arg(d, line)?;
                self.params()?;
                self.warn(
                    line,
                    format!("MakeNamedMedium \"{name}\": volumes are not supported (ignored)"),
                );
            }
            "MediumInterface" => {
                self.string_arg(d, line)?;
                if self.peek_is_str()? {
                    self.string_arg(d, line)?;
                }
                self.warn(line, "MediumInterface: volumes are not supported (ignored)");
            }
            "Attribute" => {
                let target = self.string_arg(d, line)?;
                self.params()?;
                self.warn(
                    line,
                    format!(
                        "Attribute \"{target}\": default parameters are not supported (ignored)"
                    ),
                );
            }
            "Texture" => self.texture_directive(line)?,
            "Material" => {
                let ty = self.string_arg(d, line)?;
                let p = self.params()?;
                self.state.material =
                    self.make_material(&format!("material at {}", self.here(line)), &ty, &p, line)?;
            }
            "MakeNamedMaterial" => {
                let name = self.string_arg(d, line)?;
                let p = self.params()?;
                let ty = p
                    .string("type")
                    .map_err(|m| self.err(line, m))?
                    .unwrap_or("")
                    .to_string();
                if ty.is_empty() {
                    return Err(self.err(
                        line,
                        format!("MakeNamedMaterial \"{name}\" without \"string type\""),
                    ));
                }
                let m = self.make_material(&name, &ty, &p, line)?;
                self.named_materials.insert(name, m);
            }
            "NamedMaterial" => {
                let name = self.string_arg(d, line)?;
                match self.named_materials.get(&name) {
                    Some(m) => self.state.material = *m,
                    None => {
                        return Err(
                            self.err(line, format!("NamedMaterial \"{name}\" is not defined"))
                        );
                    }
                }
            }
            "LightSource" => self.light_directive(line)?,
            "AreaLightSource" => {
                let ty = self.string_arg(d, line)?;
                let p = self.params()?;
                if ty != "diffuse" {
                    self.warn(
                        line,
                        format!("AreaLightSource \"{ty}\" is not supported (no emission)"),
                    );
                    self.state.area_light = None;
                    return Ok(());
                }
                let mut warnings = Vec::new();
                let mut ctx = Context {
                    textures: &self.textures,
                    warnings: &mut warnings,
                };
                let l = ctx
                    .colour(&p, "L", Vec3::ONE)
                    .map_err(|m| self.err(line, m))?;
                let scale = p.float("scale", 1.0).map_err(|m| self.err(line, m))?;
                let two_sided = p.bool("twosided", false).map_err(|m| self.err(line, m))?;
                for w in warnings {
                    self.warn(line, format!("AreaLightSource: {w}"));
                }
                self.unused("AreaLightSource \"diffuse\"", &p, &[]);
                let radiance = l * scale;
                if !radiance.is_finite() || radiance.min_element() < 0.0 {
                    return Err(self.err(line, format!("AreaLightSource: L × scale = {radiance} must be finite and non-negative")));
                }
                self.state.area_light = Some(Arc::new(AreaLight {
                    radiance,
                    two_sided,
                }));
            }
            "Shape" => self.shape_directive(line)?,
            "ObjectBegin" => {
                let name = self.string_arg(d, line)?;
                if self.object.is_some() {
                    return Err(self.err(line, "ObjectBegin inside another ObjectBegin"));
                }
                let at = self.here(line);
                self.stack.push((self.state.clone(), Block::Object, at));
                self.object = Some((name, Vec::new()));
            }
            "ObjectEnd" => {
                match self.stack.pop() {
                    Some((saved, Block::Object, _)) => self.state = saved,
                    _ => return Err(self.err(line, "ObjectEnd without ObjectBegin")),
                }
                let (name, shapes) = self.object.take().expect("inside an object");
                self.objects.insert(name, shapes);
            }
            "ObjectInstance" => {
                let name = self.string_arg(d, line)?;
                if self.object.is_some() {
                    return Err(self.err(line, "ObjectInstance inside ObjectBegin"));
                }
                let Some(shapes) = self.objects.get(&name) else {
                    return Err(self.err(
                        line,
                        format!("ObjectInstance \"{name}\": no object of that name"),
                    ));
                };
                let instance = self.root * self.state.ctm;
                for s in shapes {
                    self.builder.add_mesh(
                        &s.name,
                        &s.mesh.positions,
                        s.mesh.normals.as_deref(),
                        s.mesh.uvs.as_deref(),
                        &s.mesh.indices,
                        to_f32(instance * s.ctm),
                        s.material,
                    )?;
                    self.report.triangles += s.mesh.indices.len() / 3;
                }
                self.report.instances += 1;
            }
            other => return Err(self.err(line, format!("unknown directive `{other}`"))),
        }
        Ok(())
    }

    fn concat(&mut self, m: DMat4, _line: usize) {
        if !self.end_time_only {
            self.state.ctm *= m;
        }
    }

    fn camera_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("Camera", line)?;
        let p = self.params()?;
        let world_from_camera = self.state.ctm.inverse();
        self.named_coords.insert("camera".into(), world_from_camera);
        if ty != "perspective" {
            self.warn(line, format!("Camera \"{ty}\" is not supported: a perspective camera with the same transform is used"));
        }
        let fov = p.float("fov", 90.0).map_err(|m| self.err(line, m))? as f64;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.err(line, format!("Camera: fov {fov} is not in (0, 180)")));
        }
        if p.float("lensradius", 0.0).map_err(|m| self.err(line, m))? > 0.0 {
            self.warn(line, "Camera: depth of field is not supported (pinhole)");
        }
        p.touch("focaldistance");
        self.unused(&format!("Camera \"{ty}\""), &p, &[]);
        self.camera = Some(CameraSpec {
            camera_from_world: self.state.ctm,
            fov_degrees: fov,
            line: self.here(line),
        });
        Ok(())
    }

    /// pbrt's camera: camera space looks down +z with +y up and +x to the image's right; the
    /// field of view spans the image's shorter axis.
    fn finish_camera(&mut self) -> Result<(), SceneError> {
        let spec = self.camera.take().unwrap_or(CameraSpec {
            camera_from_world: DMat4::IDENTITY,
            fov_degrees: 90.0,
            line: "default camera".into(),
        });
        let w = self.root * spec.camera_from_world.inverse();
        let eye = w.transform_point3(DVec3::ZERO);
        let forward = w.transform_vector3(DVec3::Z);
        let up = w.transform_vector3(DVec3::Y);
        let right = w.transform_vector3(DVec3::X);
        if !eye.is_finite() || forward.length() < 1e-12 || forward.cross(up).length() < 1e-12 {
            return Err(SceneError::Pbrt {
                path: spec.line.clone(),
                line: 0,
                message: "the camera transform is degenerate".into(),
            });
        }
        let (fl, ul, rl) = (forward.length(), up.length(), right.length());
        let rigid = (fl - ul).abs() < 1e-6 * fl
            && (fl - rl).abs() < 1e-6 * fl
            && forward.dot(up).abs() < 1e-6 * fl * ul
            && forward.dot(right).abs() < 1e-6 * fl * rl;
        if !rigid {
            self.warnings.push((
                "the camera transform scales or shears: its rotation is used".into(),
                spec.line.clone(),
                1,
            ));
        }
        let forward = forward.normalize();
        let up = (up - forward * up.dot(forward)).normalize();
        let mirrored = forward.cross(up).dot(right) < 0.0;
        let (width, height) = self.film;
        let half = (spec.fov_degrees.to_radians() * 0.5).tan();
        // fov spans the shorter axis; ours is vertical
        let yfov = if width >= height {
            spec.fov_degrees.to_radians()
        } else {
            2.0 * (half * height as f64 / width as f64).atan()
        };
        let mut camera = Camera::look_at(
            "pbrt camera",
            eye.as_vec3(),
            (eye + forward).as_vec3(),
            up.as_vec3(),
            yfov as f32,
            width,
            height,
        );
        camera.mirrored = mirrored;
        self.builder.add_camera(camera);
        Ok(())
    }

    fn texture_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let name = self.string_arg("Texture", line)?;
        let _ty = self.string_arg("Texture", line)?;
        let class = self.string_arg("Texture", line)?;
        let p = self.params()?;
        let mut warnings = Vec::new();
        let mut ctx = Context {
            textures: &self.textures,
            warnings: &mut warnings,
        };
        let t = materials::texture(&class, &p, &mut ctx).map_err(|m| self.err(line, m))?;
        for w in warnings {
            self.warn(line, format!("Texture \"{name}\": {w}"));
        }
        if let TextureValue::Unsupported(c) = &t {
            self.warn(line, format!("Texture \"{name}\": class \"{c}\" is not supported (materials using it take their default)"));
        } else {
            self.unused(&format!("Texture \"{name}\""), &p, &[]);
        }
        self.textures.insert(name, t);
        Ok(())
    }

    fn make_material(
        &mut self,
        name: &str,
        ty: &str,
        p: &ParamList,
        line: usize,
    ) -> Result<Option<usize>, SceneError> {
        let mut warnings = Vec::new();
        let mut ctx = Context {
            textures: &self.textures,
            warnings: &mut warnings,
        };
        let m = materials::material(name, ty, p, &mut ctx).map_err(|m| self.err(line, m))?;
        for w in warnings {
            self.warn(line, format!("material \"{ty}\": {w}"));
        }
        self.unused(&format!("material \"{ty}\""), p, &[]);
        Ok(m.map(|m| {
            self.materials.push(m);
            self.materials.len() - 1
        }))
    }

    /// The builder material for the current material and area light.
    fn builder_material(&mut self) -> Result<Option<u32>, SceneError> {
        let Some(m) = self.state.material else {
            return Ok(None);
        };
        let light_key = self
            .state
            .area_light
            .as_ref()
            .map_or(0, |a| Arc::as_ptr(a) as usize);
        if let Some(&id) = self.built.get(&(m, light_key)) {
            return Ok(Some(id));
        }
        let mut mat = self.materials[m].clone();
        if let Some(a) = &self.state.area_light {
            mat.emission = a.radiance;
            mat.double_sided = a.two_sided;
            mat.name = format!("{} (emitting)", mat.name);
        }
        let id = self.builder.add_material(mat)?;
        self.built.insert((m, light_key), id);
        Ok(Some(id))
    }

    fn shape_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("Shape", line)?;
        let p = self.params()?;
        let what = format!("Shape \"{ty}\"");
        let e = |this: &Self, m: String| this.err(line, format!("{what}: {m}"));
        let mesh = match ty.as_str() {
            "trianglemesh" => shapes::triangle_mesh(&p).map_err(|m| e(self, m))?,
            "bilinearmesh" => shapes::bilinear_mesh(&p).map_err(|m| e(self, m))?,
            "plymesh" => {
                let f = p
                    .string("filename")
                    .map_err(|m| e(self, m))?
                    .ok_or_else(|| e(self, "no \"string filename\"".into()))?;
                let path = if Path::new(f).is_absolute() {
                    PathBuf::from(f)
                } else {
                    self.base_dir.join(f)
                };
                if path.extension().is_some_and(|x| x == "gz") {
                    return Err(e(
                        self,
                        format!(
                            "{}: gzip-compressed files are not supported (gunzip it first)",
                            path.display()
                        ),
                    ));
                }
                for k in ["displacement", "edgelength"] {
                    if p.touch(k) {
                        self.warn(
                            line,
                            format!("{what}: \"{k}\" (displacement) is not supported (ignored)"),
                        );
                    }
                }
                super::ply::read(&path).map_err(|m| e(self, m))?
            }
            "sphere" => {
                let radius = p.float("radius", 1.0).map_err(|m| e(self, m))?;
                let zmin = p.float("zmin", -radius).map_err(|m| e(self, m))?;
                let zmax = p.float("zmax", radius).map_err(|m| e(self, m))?;
                let phimax = p.float("phimax", 360.0).map_err(|m| e(self, m))?;
                if zmin > -radius || zmax < radius || phimax < 360.0 {
                    self.warn(
                        line,
                        format!("{what}: partial spheres (zmin, zmax, phimax) are rendered whole"),
                    );
                }
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(e(self, format!("radius {radius} must be positive")));
                }
                if self.state.area_light.is_some() && self.object.is_none() {
                    self.unused(&what, &p, &[]);
                    return self.sphere_light(radius, line);
                }
                shapes::sphere(radius)
            }
            "disk" => {
                let radius = p.float("radius", 1.0).map_err(|m| e(self, m))?;
                let height = p.float("height", 0.0).map_err(|m| e(self, m))?;
                if p.float("innerradius", 0.0).map_err(|m| e(self, m))? > 0.0 {
                    self.warn(
                        line,
                        format!("{what}: \"innerradius\" is not supported (a full disk)"),
                    );
                }
                if p.float("phimax", 360.0).map_err(|m| e(self, m))? < 360.0 {
                    self.warn(
                        line,
                        format!("{what}: \"phimax\" is not supported (a full disk)"),
                    );
                }
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(e(self, format!("radius {radius} must be positive")));
                }
                shapes::disk(radius, height)
            }
            other => {
                self.warn(
                    line,
                    format!("Shape \"{other}\" is not supported (skipped)"),
                );
                return Ok(());
            }
        };
        // parameters every shape may carry that we do not model
        for k in [
            "alpha",
            "shadowalpha",
            "emissionfilename",
            "faceIndices",
            "S",
            "tangents",
        ] {
            if p.touch(k) {
                self.warn(line, format!("{what}: \"{k}\" is not supported (ignored)"));
            }
        }
        self.unused(&what, &p, &[]);
        self.add_shape(mesh, &ty, line)
    }

    fn add_shape(&mut self, mut mesh: MeshData, ty: &str, line: usize) -> Result<(), SceneError> {
        let Some(material) = self.builder_material()? else {
            self.warn(
                line,
                "shapes with material \"interface\" are invisible (skipped)",
            );
            return Ok(());
        };
        mesh.orient(self.state.reverse);
        self.report.shapes += 1;
        let name = format!("{ty} at {}", self.here(line));
        if self.object.is_some() {
            // pbrt ignores area lights inside instances: the material without emission
            let material = if self.state.area_light.is_some() {
                self.warn(line, "area lights inside ObjectBegin are not supported (pbrt ignores them too): not emitting");
                let saved = self.state.area_light.take();
                let id = self.builder_material()?.expect("a material");
                self.state.area_light = saved;
                id
            } else {
                material
            };
            let (_, shapes) = self.object.as_mut().expect("inside an object");
            shapes.push(Instanced {
                mesh: Arc::new(mesh),
                ctm: self.state.ctm,
                material,
                name,
            });
            return Ok(());
        }
        self.report.triangles += mesh.indices.len() / 3;
        self.builder
            .add_mesh(
                &name,
                &mesh.positions,
                mesh.normals.as_deref(),
                mesh.uvs.as_deref(),
                &mesh.indices,
                to_f32(self.root * self.state.ctm),
                material,
            )
            .map_err(|e| self.err(line, e.to_string()))
    }

    /// An emitting pbrt sphere becomes one of our sphere lights (its surface is black here).
    fn sphere_light(&mut self, radius: f32, line: usize) -> Result<(), SceneError> {
        let m = self.root * self.state.ctm;
        let center = m.transform_point3(DVec3::ZERO);
        let scales = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| m.transform_vector3(a).length());
        let s = (scales[0] + scales[1] + scales[2]) / 3.0;
        if scales.iter().any(|x| (x - s).abs() > 1e-4 * s) {
            self.warn(line, "Shape \"sphere\" light under a non-uniform scale: a sphere of the mean radius is used");
        }
        if self.state.reverse {
            self.warn(
                line,
                "Shape \"sphere\" light with ReverseOrientation: it emits outwards here",
            );
        }
        let light = self.state.area_light.clone().expect("an area light");
        if let Some(mi) = self.state.material {
            let mat = &self.materials[mi];
            if mat.base_color.max_element() > 0.0 {
                self.warn(line, "Shape \"sphere\" light: its surface is rendered black (the material is not used)");
            }
        }
        self.builder
            .add_sphere_light(
                center.as_vec3(),
                (radius as f64 * s) as f32,
                light.radiance,
                None,
            )
            .map_err(|e| self.err(line, e.to_string()))?;
        self.report.sphere_lights += 1;
        self.report.shapes += 1;
        Ok(())
    }

    fn light_directive(&mut self, line: usize) -> Result<(), SceneError> {
        let ty = self.string_arg("LightSource", line)?;
        let p = self.params()?;
        let what = format!("LightSource \"{ty}\"");
        let e = |this: &Self, m: String| this.err(line, format!("{what}: {m}"));
        let m = self.root * self.state.ctm;
        let mut warnings = Vec::new();
        let mut ctx = Context {
            textures: &self.textures,
            warnings: &mut warnings,
        };
        let scale = p.float("scale", 1.0).map_err(|m| e(self, m))?;
        let result = match ty.as_str() {
            "point" | "spot" => {
                let i = ctx.colour(&p, "I", Vec3::ONE).map_err(|m| e(self, m))? * scale;
                let from = p.point("from", Vec3::ZERO).map_err(|m| e(self, m))?;
                let position = m.transform_point3(from.as_dvec3()).as_vec3();
                let spot = if ty == "spot" {
                    let to = p.point("to", Vec3::Z).map_err(|m| e(self, m))?;
                    let cone = p.float("coneangle", 30.0).map_err(|m| e(self, m))?;
                    let delta = p.float("conedelta", 5.0).map_err(|m| e(self, m))?;
                    let dir = m
                        .transform_vector3((to - from).as_dvec3())
                        .normalize()
                        .as_vec3();
                    if !dir.is_finite() {
                        return Err(e(self, "\"from\" and \"to\" coincide".into()));
                    }
                    let outer = cone.clamp(0.0, 90.0).to_radians();
                    let inner = (cone - delta)
                        .clamp(0.0, cone.clamp(0.0, 90.0))
                        .to_radians();
                    Some(SpotCone {
                        direction: dir,
                        cos_inner: inner.cos(),
                        cos_outer: outer.cos(),
                    })
                } else {
                    None
                };
                if p.touch("power") {
                    warnings.push("\"power\" is not supported (I × scale is used)".into());
                }
                if spot.is_some() {
                    warnings.push(
                        "the spot falloff follows glTF's smooth curve between the cone angles"
                            .into(),
                    );
                    self.report.spot_lights += 1;
                } else {
                    self.report.point_lights += 1;
                }
                self.builder.add_point_light(position, i, spot)
            }
            "distant" => {
                let l = ctx.colour(&p, "L", Vec3::ONE).map_err(|m| e(self, m))? * scale;
                let from = p.point("from", Vec3::ZERO).map_err(|m| e(self, m))?;
                let to = p.point("to", Vec3::Z).map_err(|m| e(self, m))?;
                let dir = m.transform_vector3((from - to).as_dvec3()).as_vec3();
                if p.touch("illuminance") {
                    warnings.push("\"illuminance\" is not supported (L × scale is used)".into());
                }
                self.report.distant_lights += 1;
                self.builder.add_distant_light(dir, l)
            }
            other => {
                for q in &p.params {
                    p.touch(&q.name);
                }
                self.warn(
                    line,
                    format!("LightSource \"{other}\" is not supported (skipped)"),
                );
                return Ok(());
            }
        };
        for w in warnings {
            self.warn(line, format!("{what}: {w}"));
        }
        self.unused(&what, &p, &[]);
        result.map_err(|err| self.err(line, err.to_string()))
    }
}

/// pbrt's `LookAt`: the camera-from-world (world-to-look) transform.
fn look_at(pos: DVec3, look: DVec3, up: DVec3) -> Result<DMat4, String> {
    let dir = (look - pos).normalize();
    let up = up.normalize();
    if !dir.is_finite() || !up.is_finite() || up.cross(dir).length() < 1e-12 {
        return Err(
            "LookAt: the up vector and the viewing direction are parallel (or zero)".into(),
        );
    }
    let right = up.cross(dir).normalize();
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        pos.extend(1.0),
    );
    Ok(world_from_camera.inverse())
}
