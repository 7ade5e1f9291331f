//! The graphics state's directives: `WorldBegin`, the `AttributeBegin`/`TransformBegin` blocks,
//! the transforms (`Translate` … `ConcatTransform`, `LookAt`), named coordinate systems,
//! `ActiveTransform` (start time only: no motion blur) and `ReverseOrientation`.
use super::Parser;
use super::records::Block;
use crate::pbrt::tokenizer::Token;
use glam::{DMat4, DVec3};
use render_core::error::SceneError;

impl Parser<'_> {
    /// `WorldBegin`: the transform back to identity, named `world`.
    pub(super) fn world_begin(&mut self) {
        self.state.ctm = DMat4::IDENTITY;
        self.named_coords.insert("world".into(), DMat4::IDENTITY);
    }

    /// `AttributeBegin` (saves the whole state) or `TransformBegin` (its transform only).
    pub(super) fn begin_block(&mut self, d: &str, line: usize) {
        let kind = if d == "AttributeBegin" {
            Block::Attribute
        } else {
            Block::Transform
        };
        let at = self.here(line);
        self.stack.push((self.state.clone(), kind, at));
    }

    /// `AttributeEnd` or `TransformEnd`, which must close a block of its own kind.
    pub(super) fn end_block(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        match self.stack.pop() {
            Some((saved, Block::Attribute, _)) if d == "AttributeEnd" => self.state = saved,
            Some((saved, Block::Transform, _)) if d == "TransformEnd" => self.state.ctm = saved.ctm,
            Some((_, _, at)) => {
                return Err(self.err(line, format!("{d} does not match the block opened at {at}")));
            }
            None => return Err(self.err(line, format!("{d} without a matching begin"))),
        }
        Ok(())
    }

    /// `Identity`, `Translate`, `Scale`, `Rotate`, `LookAt`, `Transform`, `ConcatTransform`.
    pub(super) fn transform(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        match d {
            "Identity" => self.state.ctm = DMat4::IDENTITY,
            "Translate" => {
                let v = self.numbers(d, 3, line)?;
                self.concat(DMat4::from_translation(DVec3::new(v[0], v[1], v[2])));
            }
            "Scale" => {
                let v = self.numbers(d, 3, line)?;
                self.concat(DMat4::from_scale(DVec3::new(v[0], v[1], v[2])));
            }
            "Rotate" => {
                let v = self.numbers(d, 4, line)?;
                let axis = DVec3::new(v[1], v[2], v[3]);
                if axis.length_squared() == 0.0 {
                    return Err(self.err(line, "Rotate about a zero axis"));
                }
                self.concat(DMat4::from_axis_angle(axis.normalize(), v[0].to_radians()));
            }
            "LookAt" => {
                let v = self.numbers(d, 9, line)?;
                let m = look_at(
                    DVec3::new(v[0], v[1], v[2]),
                    DVec3::new(v[3], v[4], v[5]),
                    DVec3::new(v[6], v[7], v[8]),
                )
                .map_err(|m| self.err(line, m))?;
                self.concat(m);
            }
            "Transform" | "ConcatTransform" => {
                let v = self.numbers(d, 16, line)?;
                let m = DMat4::from_cols_slice(&v);
                if d == "Transform" {
                    if !self.end_time_only {
                        self.state.ctm = m;
                    }
                } else {
                    self.concat(m);
                }
            }
            other => unreachable!("`{other}` is not a transform directive"),
        }
        Ok(())
    }

    /// Post-multiplies the current transform (unless only end-time transforms are active).
    fn concat(&mut self, m: DMat4) {
        if !self.end_time_only {
            self.state.ctm *= m;
        }
    }

    /// `CoordinateSystem` names the current transform; `CoordSysTransform` makes a named one
    /// current (`camera` is named by the `Camera` directive).
    pub(super) fn coordinate_system(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        let n = self.string_arg(d, line)?;
        if d == "CoordinateSystem" {
            self.named_coords.insert(n, self.state.ctm);
            return Ok(());
        }
        match self.named_coords.get(&n) {
            Some(m) => self.state.ctm = *m,
            None => self.warn(
                line,
                format!("CoordSysTransform: no coordinate system named `{n}` (ignored)"),
            ),
        }
        Ok(())
    }

    /// `ActiveTransform`: with `EndTime`, transforms are ignored until it changes back.
    pub(super) fn active_transform(&mut self, line: usize) -> Result<(), SceneError> {
        let which = match self.next_in_file()? {
            Some((Token::Word(w), _)) => w,
            _ => {
                return Err(self.err(line, "ActiveTransform expects StartTime, EndTime or All"));
            }
        };
        self.end_time_only = which == "EndTime";
        if which != "StartTime" {
            self.warn(line, "ActiveTransform: motion blur is not supported; only start-time transforms are used");
        }
        Ok(())
    }

    /// `TransformTimes`: read and ignored (no motion blur).
    pub(super) fn transform_times(&mut self, d: &str, line: usize) -> Result<(), SceneError> {
        self.numbers(d, 2, line)?;
        self.warn(
            line,
            "TransformTimes: motion blur is not supported (ignored)",
        );
        Ok(())
    }

    /// `ReverseOrientation`: flips the normals of the shapes that follow.
    pub(super) fn reverse_orientation(&mut self) {
        self.state.reverse = !self.state.reverse;
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
