//! Shapes and object instancing: `Shape` (triangle, bilinear and PLY meshes, spheres, disks;
//! an emitting sphere becomes a sphere light), `ObjectBegin`/`ObjectEnd` (shapes recorded) and
//! `ObjectInstance` (recorded shapes added under the current transform).
use super::records::{Block, Instanced};
use super::{Parser, to_f32};
use crate::pbrt::ply;
use crate::pbrt::shapes::{self, MeshData};
use glam::DVec3;
use render_core::error::SceneError;
use std::path::{Path, PathBuf};
use std::sync::Arc;

impl Parser<'_> {
    /// `Shape "type" params`.
    pub(super) fn shape_directive(&mut self, line: usize) -> Result<(), SceneError> {
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
                ply::read(&path).map_err(|m| e(self, m))?
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

    /// Adds a mesh under the current transform and material, or records it inside an object.
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

    /// `ObjectBegin "name"`: a block whose shapes are recorded, not added.
    pub(super) fn object_begin(&mut self, line: usize) -> Result<(), SceneError> {
        let name = self.string_arg("ObjectBegin", line)?;
        if self.object.is_some() {
            return Err(self.err(line, "ObjectBegin inside another ObjectBegin"));
        }
        let at = self.here(line);
        self.stack.push((self.state.clone(), Block::Object, at));
        self.object = Some((name, Vec::new()));
        Ok(())
    }

    /// `ObjectEnd`: the recorded shapes are kept under the object's name.
    pub(super) fn object_end(&mut self, line: usize) -> Result<(), SceneError> {
        match self.stack.pop() {
            Some((saved, Block::Object, _)) => self.state = saved,
            _ => return Err(self.err(line, "ObjectEnd without ObjectBegin")),
        }
        let (name, shapes) = self.object.take().expect("inside an object");
        self.objects.insert(name, shapes);
        Ok(())
    }

    /// `ObjectInstance "name"`: the object's shapes under the current transform.
    pub(super) fn object_instance(&mut self, line: usize) -> Result<(), SceneError> {
        let name = self.string_arg("ObjectInstance", line)?;
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
        Ok(())
    }
}
