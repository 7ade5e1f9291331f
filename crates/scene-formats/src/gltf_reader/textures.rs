//! Textures: a glTF image decoded once per colour space (sRGB or linear) into a linear RGBA
//! [`Texture`]; wrap modes are read as repeat.
use super::Loader;
use glam::Vec4;
use render_core::error::SceneError;
use render_core::texture::{Texture, srgb_to_linear};
use std::sync::Arc;

impl Loader<'_> {
    /// The decoded texture of `tex`, in sRGB (colours) or linear (data) encoding.
    pub(super) fn texture(
        &mut self,
        tex: &gltf::Texture,
        srgb: bool,
    ) -> Result<Arc<Texture>, SceneError> {
        let image = tex.source();
        let key = (image.index(), srgb);
        let sampler = tex.sampler();
        let repeat = gltf::texture::WrappingMode::Repeat;
        if sampler.wrap_s() != repeat || sampler.wrap_t() != repeat {
            self.report
                .warn("texture wrap modes other than repeat read as repeat".into());
        }
        if let Some(t) = self.textures.get(&key) {
            return Ok(t.clone());
        }
        self.check_image_source(image.index())
            .map_err(|e| self.err(format!("image {}: {e}", image.index())))?;
        let data = gltf::image::Data::from_source(image.source(), Some(self.base), self.buffers)
            .map_err(|e| self.err(format!("image {}: {e}", image.index())))?;
        let t = Arc::new(
            convert_image(&data, srgb)
                .map_err(|e| self.err(format!("image {}: {e}", image.index())))?,
        );
        self.textures.insert(key, t.clone());
        Ok(t)
    }

    /// What the gltf crate's image reading assumes unchecked (it panics otherwise): a buffer
    /// view image has a MIME type and lies inside its buffer; any other has a URI.
    fn check_image_source(&self, index: usize) -> Result<(), String> {
        let json = self.doc.as_json();
        let img = json.images.get(index).ok_or("does not exist")?;
        match &img.buffer_view {
            Some(v) => {
                if img.mime_type.is_none() {
                    return Err("a buffer view image needs a mimeType".into());
                }
                let view = json
                    .buffer_views
                    .get(v.value())
                    .ok_or("its buffer view does not exist")?;
                let data = self
                    .buffers
                    .get(view.buffer.value())
                    .ok_or("its buffer does not exist")?;
                let end = (view.byte_offset.map_or(0, |o| o.0) as usize)
                    .checked_add(view.byte_length.0 as usize);
                if end.is_none_or(|e| e > data.0.len()) {
                    return Err("its buffer view runs past its buffer".into());
                }
                Ok(())
            }
            None if img.uri.is_none() => Err("has neither a uri nor a bufferView".into()),
            None => Ok(()),
        }
    }
}

/// A decoded glTF image as a linear RGBA texture (grey images replicate to RGB).
fn convert_image(img: &gltf::image::Data, srgb: bool) -> Result<Texture, String> {
    use gltf::image::Format;
    let (w, h) = (img.width, img.height);
    let n = w as usize * h as usize;
    if n == 0 {
        return Err("empty image".into());
    }
    let lut: Vec<f32> = (0..256)
        .map(|i| {
            if srgb {
                srgb_to_linear(i as f32 / 255.0)
            } else {
                i as f32 / 255.0
            }
        })
        .collect();
    let c8 = |v: u8| lut[v as usize];
    let c16 = |b: &[u8]| {
        let v = u16::from_ne_bytes([b[0], b[1]]) as f32 / 65535.0;
        if srgb { srgb_to_linear(v) } else { v }
    };
    let a16 = |b: &[u8]| u16::from_ne_bytes([b[0], b[1]]) as f32 / 65535.0;
    let f32c = |b: &[u8]| f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
    let (channels, bytes_per) = match img.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        Format::R32G32B32FLOAT => (3, 4),
        Format::R32G32B32A32FLOAT => (4, 4),
    };
    let stride = channels * bytes_per;
    if img.pixels.len() < n * stride {
        return Err(format!(
            "{} bytes of pixel data for {w}×{h} {:?}",
            img.pixels.len(),
            img.format
        ));
    }
    let texels = img.pixels[..n * stride]
        .chunks_exact(stride)
        .map(|p| {
            let ch = |k: usize| &p[k * bytes_per..(k + 1) * bytes_per];
            let v = |k: usize| match bytes_per {
                1 => c8(ch(k)[0]),
                2 => c16(ch(k)),
                _ => f32c(ch(k)),
            };
            let a = |k: usize| match bytes_per {
                1 => ch(k)[0] as f32 / 255.0,
                2 => a16(ch(k)),
                _ => f32c(ch(k)),
            };
            match channels {
                1 => Vec4::new(v(0), v(0), v(0), 1.0),
                2 => Vec4::new(v(0), v(0), v(0), a(1)),
                3 => Vec4::new(v(0), v(1), v(2), 1.0),
                _ => Vec4::new(v(0), v(1), v(2), a(3)),
            }
        })
        .collect();
    Ok(Texture::new(w, h, texels))
}
