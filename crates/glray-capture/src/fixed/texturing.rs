//! TextureUnit (Mesa's texobj.c, teximage.c, texparam.c, texenv.c, texgen.c): the texture
//! objects a share group holds, which are bound and enabled, their images and sampling state,
//! the texture environment and texture coordinate generation. Their commands, and what
//! glPopAttrib takes back. Texture objects shared with other contexts are changed in place only
//! when no frame holds them; else a copy is changed (`Arc::make_mut`).

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DMat4, DVec4, Vec4};
use glray_core::trace::Value;
use glray_gl::{
    GL_ENABLE_BIT, GL_EYE_LINEAR, GL_EYE_PLANE, GL_OBJECT_PLANE, GL_S, GL_T, GL_TEXTURE_1D, GL_TEXTURE_2D,
    GL_TEXTURE_BIT, GL_TEXTURE_ENV_COLOR, GL_TEXTURE_ENV_MODE, GL_TEXTURE_GEN_MODE, GL_TEXTURE_GEN_S, GL_TEXTURE_GEN_T,
    GL_UNSIGNED_INT,
};
use glray_scene::surface::TexEnvMode;
use glray_scene::texture::{Level, Texture};

use crate::args::{self, color_param, floats};
use crate::error::{GlError, GlResult};
use crate::ops::Op;
use crate::texture::{self, Unpack};

/// The texture objects of a share group, by name.
pub(crate) type Textures = HashMap<u32, Arc<Texture>>;

/// Texture coordinate generation of one coordinate (s or t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TexGen {
    pub(crate) enabled: bool,
    pub(crate) mode: u32,
    pub(crate) object_plane: DVec4,
    pub(crate) eye_plane: DVec4,
}

/// A context's texturing state (texture unit 0), with GL's initial values.
#[derive(Debug, Clone)]
pub(crate) struct TextureUnit {
    pub(crate) texture_2d: bool,
    pub(crate) bound_texture: u32,
    /// GL_TEXTURE_1D's enable and binding (a 2D texture, enabled, takes precedence).
    pub(crate) texture_1d: bool,
    pub(crate) bound_texture_1d: u32,
    pub(crate) env_mode: TexEnvMode,
    pub(crate) env_color: Vec4,
    pub(crate) texgen: [TexGen; 2],
}

impl Default for TextureUnit {
    fn default() -> Self {
        let texgen = TexGen { enabled: false, mode: GL_EYE_LINEAR, object_plane: DVec4::X, eye_plane: DVec4::X };
        TextureUnit {
            texture_2d: false,
            bound_texture: 0,
            texture_1d: false,
            bound_texture_1d: 0,
            env_mode: TexEnvMode::Modulate,
            env_color: Vec4::ZERO,
            texgen: [texgen, TexGen { object_plane: DVec4::Y, eye_plane: DVec4::Y, ..texgen }],
        }
    }
}

impl TextureUnit {
    /// Follows a texturing command (`Concern::TextureUnit`) on the share group's `objects`, with
    /// the unpack state of the moment (images) and the modelview (eye planes).
    pub(crate) fn command(
        &mut self,
        objects: &mut Textures,
        op: Op,
        ty: u32,
        a: &[Value],
        unpack: &Unpack,
        modelview: &DMat4,
    ) -> GlResult {
        match op {
            Op::BindTexture => match args::uint(a, 0) {
                GL_TEXTURE_2D => self.bound_texture = args::uint(a, 1),
                GL_TEXTURE_1D => self.bound_texture_1d = args::uint(a, 1),
                _ => {}
            },
            Op::DeleteTextures => {
                for name in args::array(args::bytes(a, 1), GL_UNSIGNED_INT, args::int(a, 0).max(0) as usize) {
                    let name = name as u32;
                    objects.remove(&name);
                    if self.bound_texture == name {
                        self.bound_texture = 0;
                    }
                    if self.bound_texture_1d == name {
                        self.bound_texture_1d = 0;
                    }
                }
            }
            Op::TexImage2D => self.tex_image(objects, a, false, unpack)?,
            Op::TexSubImage2D => self.tex_image(objects, a, true, unpack)?,
            Op::TexImage1D | Op::TexSubImage1D => {
                // A 1D texture is a 2D one of one row: the arguments a 2D call would have.
                let (i, u) = (|k: usize| Value::Int(args::int(a, k)), |k: usize| Value::Int(args::uint(a, k) as i64));
                let (target, level) = (Value::Int(GL_TEXTURE_1D as i64), i(1));
                let data = a.get(if op == Op::TexImage1D { 7 } else { 6 }).cloned().unwrap_or(Value::Null);
                let a2 = if op == Op::TexImage1D {
                    // (internal format, width, height 1, border, format, type, pixels)
                    vec![target, level, u(2), i(3), Value::Int(1), i(4), u(5), u(6), data]
                } else {
                    // (x, y 0, width, height 1, format, type, pixels)
                    vec![target, level, i(2), Value::Int(0), i(3), Value::Int(1), u(4), u(5), data]
                };
                self.tex_image(objects, &a2, op == Op::TexSubImage1D, unpack)?
            }
            Op::TexParameter => {
                let target = args::uint(a, 0);
                if target == GL_TEXTURE_2D || target == GL_TEXTURE_1D {
                    let value = floats(a, 2, ty, 1).first().copied().unwrap_or(0.0);
                    // Only a value that changes touches the texture: a change is a new version
                    // to the renderer (no unchanged frame shown again), and a texture this frame
                    // has drawn with is copied to be changed, every level of it. Programs set
                    // the same parameters before every draw (VTK does).
                    let name = self.bound(target);
                    // The sampling state alone (every field but the levels is a number).
                    let mut set = match objects.get(&name) {
                        Some(t) => Texture { levels: Vec::new(), ..**t },
                        None => Texture { version: 0, ..Texture::default() },
                    };
                    let before = Texture { levels: Vec::new(), ..set };
                    match texture::set_parameter(&mut set, args::uint(a, 1), value) {
                        Some(Err(e)) => return Err(e),
                        Some(Ok(())) if set != before => {
                            let t = self.texture_mut(objects, target);
                            (t.min_filter, t.mag_filter, t.wrap_s, t.wrap_t, t.lod) =
                                (set.min_filter, set.mag_filter, set.wrap_s, set.wrap_t, set.lod);
                        }
                        _ => {}
                    }
                }
            }
            Op::TexEnv => match args::uint(a, 1) {
                GL_TEXTURE_ENV_MODE => {
                    let mode = floats(a, 2, ty, 1).first().copied().unwrap_or(0.0) as u32;
                    self.env_mode = TexEnvMode::from_gl(mode).ok_or(GlError::InvalidEnum)?
                }
                GL_TEXTURE_ENV_COLOR => self.env_color = color_param(a, 2, ty).as_vec4(),
                _ => {}
            },
            Op::TexGen => {
                let coord = match args::uint(a, 0) {
                    GL_S => 0,
                    GL_T => 1,
                    _ => return Ok(()), // r and q are not generated by glray yet
                };
                let v = floats(a, 2, ty, 4);
                match args::uint(a, 1) {
                    GL_TEXTURE_GEN_MODE => self.texgen[coord].mode = v.first().copied().unwrap_or(0.0) as u32,
                    GL_OBJECT_PLANE => {
                        if let Ok(p) = <[f64; 4]>::try_from(v) {
                            self.texgen[coord].object_plane = DVec4::from_array(p)
                        }
                    }
                    GL_EYE_PLANE => {
                        if let Ok(p) = <[f64; 4]>::try_from(v) {
                            // Eye planes are taken through the inverse modelview of the moment.
                            self.texgen[coord].eye_plane = modelview.inverse().transpose() * DVec4::from_array(p);
                        }
                    }
                    _ => return Err(GlError::InvalidEnum),
                }
            }
            _ => unreachable!("{op:?} is not a texturing command"),
        }
        Ok(())
    }

    /// glEnable/glDisable of a capability of texturing's; false for any other.
    pub(crate) fn set_cap(&mut self, cap: u32, on: bool) -> bool {
        match cap {
            GL_TEXTURE_2D => self.texture_2d = on,
            GL_TEXTURE_1D => self.texture_1d = on,
            GL_TEXTURE_GEN_S => self.texgen[0].enabled = on,
            GL_TEXTURE_GEN_T => self.texgen[1].enabled = on,
            _ => return false,
        }
        true
    }

    /// glPopAttrib: takes back what the groups in `mask` saved.
    pub(crate) fn restore(&mut self, mask: u32, s: &TextureUnit) {
        if mask & (GL_TEXTURE_BIT | GL_ENABLE_BIT) != 0 {
            self.texture_2d = s.texture_2d;
            self.texture_1d = s.texture_1d;
            self.texgen[0].enabled = s.texgen[0].enabled;
            self.texgen[1].enabled = s.texgen[1].enabled;
        }
        if mask & GL_TEXTURE_BIT != 0 {
            self.bound_texture = s.bound_texture;
            self.bound_texture_1d = s.bound_texture_1d;
            self.env_mode = s.env_mode;
            self.env_color = s.env_color;
            self.texgen = s.texgen;
        }
    }

    /// The texture a draw samples: GL_TEXTURE_2D, enabled, takes precedence over GL_TEXTURE_1D.
    pub(crate) fn enabled_texture(&self) -> Option<u32> {
        if self.texture_2d {
            Some(self.bound_texture)
        } else {
            self.texture_1d.then_some(self.bound_texture_1d)
        }
    }

    /// The texture bound to `target` (GL_TEXTURE_2D or GL_TEXTURE_1D).
    fn bound(&self, target: u32) -> u32 {
        if target == GL_TEXTURE_1D {
            self.bound_texture_1d
        } else {
            self.bound_texture
        }
    }

    /// The bound texture, to be changed: in place when nothing else holds it (a frame drawn
    /// with it, until the frame is taken or cleared), else a copy.
    fn texture_mut<'t>(&self, objects: &'t mut Textures, target: u32) -> &'t mut Texture {
        let t = Arc::make_mut(objects.entry(self.bound(target)).or_default());
        t.changed();
        t
    }

    /// The bound texture, its level `level` about to be replaced whole (a new image), with room
    /// for that level. A texture a frame still holds is copied, as `Arc::make_mut` would, but
    /// without the texels of the level being replaced: a program uploading a 2048x2048 image
    /// every frame had the old 64 MB copied only to be thrown away.
    pub(crate) fn texture_to_replace<'t>(
        &self,
        objects: &'t mut Textures,
        target: u32,
        level: usize,
    ) -> &'t mut Texture {
        let t = objects.entry(self.bound(target)).or_default();
        if Arc::get_mut(t).is_none() {
            // Every field named, so that a new one is not forgotten here.
            let Texture { levels, base_format, min_filter, mag_filter, wrap_s, wrap_t, one_d, lod, version } = &**t;
            let levels =
                levels.iter().enumerate().map(|(i, l)| if i == level { Level::default() } else { l.clone() }).collect();
            let (base_format, min_filter, mag_filter, wrap_s, wrap_t, one_d, lod) =
                (*base_format, *min_filter, *mag_filter, *wrap_s, *wrap_t, *one_d, *lod);
            let version = *version;
            *t = Arc::new(Texture { levels, base_format, min_filter, mag_filter, wrap_s, wrap_t, one_d, lod, version });
        }
        let t = Arc::get_mut(t).expect("a texture held here alone");
        t.changed();
        if t.levels.len() <= level {
            t.levels.resize(level + 1, Level::default());
        }
        t
    }

    fn tex_image(&self, objects: &mut Textures, a: &[Value], sub: bool, unpack: &Unpack) -> GlResult {
        let target = args::uint(a, 0);
        if target != GL_TEXTURE_2D && target != GL_TEXTURE_1D {
            return Ok(()); // proxies, cube maps: not captured
        }
        let level = args::int(a, 1);
        if !(0..16).contains(&level) {
            return Err(GlError::InvalidValue);
        }
        let level = level as usize;
        if sub {
            let (x, y, w, h) = (args::int(a, 2), args::int(a, 3), args::int(a, 4), args::int(a, 5));
            let (format, ty, data) = (args::uint(a, 6), args::uint(a, 7), args::bytes(a, 8));
            let Some(texels) = texture::decode(w.max(0) as usize, h.max(0) as usize, format, ty, unpack, data) else {
                return Ok(());
            };
            let t = self.texture_mut(objects, target);
            let base = t.base_format;
            let Some(l) = t.levels.get_mut(level) else { return Err(GlError::InvalidOperation) };
            for row in 0..h.max(0) {
                for col in 0..w.max(0) {
                    let (tx, ty) = ((x + col) as usize, (y + row) as usize);
                    if tx < l.width && ty < l.height {
                        l.texels[ty * l.width + tx] = texture::to_base(texels[(row * w + col) as usize], base);
                    }
                }
            }
            return Ok(());
        }
        let internal = args::uint(a, 2);
        let (w, h) = (args::int(a, 3), args::int(a, 4));
        if w < 0 || h < 0 {
            return Err(GlError::InvalidValue);
        }
        let (format, ty, data) = (args::uint(a, 6), args::uint(a, 7), args::bytes(a, 8));
        let base = texture::base_format(internal);
        let (w, h) = (w as usize, h as usize);
        let t = self.texture_to_replace(objects, target, level);
        // Into the replaced level's memory (when no frame holds the texture), unless that is
        // over 16 MB and four times what this image needs.
        let mut texels = std::mem::take(&mut t.levels[level].texels);
        if texels.capacity() > (1 << 20).max(4 * w * h) {
            texels = Vec::new();
        }
        if texture::decode_into(&mut texels, w, h, format, ty, unpack, data).is_some() {
            texels.iter_mut().for_each(|c| *c = texture::to_base(*c, base));
        } else {
            texels.clear();
            texels.resize(w * h, Vec4::ONE);
        }
        if level == 0 {
            t.base_format = base;
        }
        t.one_d = target == GL_TEXTURE_1D;
        t.levels[level] = Level { width: w, height: h, texels };
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixed::tests::*;
    use crate::fixed::Context;
    use glam::Vec4;
    use glray_core::trace::Value;
    use glray_gl::*;

    use glray_scene::texture::{Filter, Wrap};

    #[test]
    fn a_new_image_leaves_a_held_texture_alone_and_keeps_the_other_levels() {
        let mut c = context();
        call(&mut c, "glBindTexture", &[i(GL_TEXTURE_2D as i64), i(7)]);
        call(&mut c, "glTexParameteri", &[i(GL_TEXTURE_2D as i64), i(0x2801), i(GL_NEAREST as i64)]); // MIN_FILTER NEAREST
        tex_image(&mut c, 0, 2, 0x1908, [255, 0, 0, 255]);
        tex_image(&mut c, 1, 1, 0x1908, [0, 255, 0, 255]);
        // A frame still holds the texture when the program uploads level 0 again.
        let held = c.shared.textures[&7].clone();
        tex_image(&mut c, 0, 2, 0x1908, [0, 0, 255, 255]);
        let now = &c.shared.textures[&7];
        let texel = |t: &Texture, level: usize| t.levels[level].texels[0];
        assert_eq!(texel(&held, 0), Vec4::new(1.0, 0.0, 0.0, 1.0), "the held texture keeps its image");
        assert_eq!(texel(now, 0), Vec4::new(0.0, 0.0, 1.0, 1.0));
        assert_eq!(texel(now, 1), texel(&held, 1), "the other level is kept");
        assert_eq!(now.levels.len(), 2);
        assert_eq!(now.min_filter, held.min_filter);
        assert_eq!(now.min_filter, Filter::Nearest);
        assert_eq!(c.errors.take(), 0);
    }
    #[test]
    fn a_sub_image_changes_a_texture_in_place_unless_a_frame_holds_it() {
        let mut c = context();
        let tex = i(GL_TEXTURE_2D as i64);
        call(&mut c, "glBindTexture", &[tex.clone(), i(5)]);
        call(&mut c, "glTexParameteri", &[tex.clone(), i(0x2801), i(GL_NEAREST as i64)]); // MIN_FILTER NEAREST
        tex_image(&mut c, 0, 2, 0x1908, [255, 0, 0, 255]);
        call(&mut c, "glEnable", std::slice::from_ref(&tex));
        let sub = |c: &mut Context, texel: [u8; 4]| {
            // One texel at (0, 0), GL_RGBA bytes.
            let part = [tex.clone(), i(0), i(0), i(0), i(1), i(1), i(0x1908), i(0x1401)];
            call(c, "glTexSubImage2D", &[&part[..], &[Value::Blob(&texel)]].concat());
        };
        let first = c.shared.textures[&5].clone();
        let (address, version) = (Arc::as_ptr(&first), first.version);
        drop(first);
        // Nothing else holds it: changed in place, a new version.
        sub(&mut c, [0, 0, 255, 255]);
        let now = &c.shared.textures[&5];
        assert_eq!(Arc::as_ptr(now), address, "in place");
        assert_ne!(now.version, version);
        assert_eq!(now.levels[0].texels[0], Vec4::new(0.0, 0.0, 1.0, 1.0));
        // A draw of this frame holds it: the frame keeps what it drew with.
        triangle(&mut c, true);
        sub(&mut c, [0, 255, 0, 255]);
        let frame = c.frame();
        let drawn = frame.surfaces[frame.triangles[0].surface as usize].texturing.as_ref().unwrap();
        let now = &c.shared.textures[&5];
        assert!(!Arc::ptr_eq(&drawn.texture, now));
        assert_eq!(drawn.texture.levels[0].texels[0], Vec4::new(0.0, 0.0, 1.0, 1.0));
        assert_eq!(now.levels[0].texels[0], Vec4::new(0.0, 1.0, 0.0, 1.0));
        assert_ne!(drawn.texture.version, now.version);
        assert_eq!(c.errors.take(), 0);
    }
    #[test]
    fn an_image_of_the_same_size_is_decoded_into_the_last_ones_memory() {
        let mut c = context();
        let tex = i(GL_TEXTURE_2D as i64);
        call(&mut c, "glBindTexture", &[tex.clone(), i(6)]);
        let upload = |c: &mut Context, size: i64, format: i64, texel: [u8; 4]| {
            tex_image(c, 0, size, format, texel);
            let level = &c.shared.textures[&6].levels[0];
            (level.texels.capacity(), level.texels.clone())
        };
        upload(&mut c, 4, 0x1908, [255, 0, 0, 255]);
        let (_, texels) = upload(&mut c, 4, 0x1908, [0, 0, 255, 255]);
        assert_eq!(texels, vec![Vec4::new(0.0, 0.0, 1.0, 1.0); 16]);
        // Smaller: in the 4x4 image's memory (a new vector would hold 4).
        let (room, texels) = upload(&mut c, 2, 0x1908, [0, 255, 0, 255]);
        assert!(room >= 16, "room for {room}");
        assert_eq!(texels, vec![Vec4::new(0.0, 1.0, 0.0, 1.0); 4]);
        // A format glray cannot read: white, as before (nothing of the last image is left).
        let (_, texels) = upload(&mut c, 2, 0x8000, [0, 255, 0, 255]); // not a format
        assert_eq!(texels, vec![Vec4::ONE; 4]);
    }
    #[test]
    fn setting_a_texture_parameter_to_its_value_leaves_the_texture_as_it_is() {
        let mut c = context();
        let tex = i(GL_TEXTURE_2D as i64);
        call(&mut c, "glBindTexture", &[tex.clone(), i(3)]);
        call(&mut c, "glTexParameteri", &[tex.clone(), i(0x2801), i(GL_LINEAR as i64)]); // MIN_FILTER LINEAR
        let held = c.shared.textures[&3].clone();
        // The same value again, and a parameter glray does not follow: the same texture (no
        // copy; the renderer sees the frame unchanged).
        call(&mut c, "glTexParameteri", &[tex.clone(), i(0x2801), i(0x2601)]);
        call(&mut c, "glTexParameterf", &[tex.clone(), i(0x2801), f(f64::from(0x2601))]);
        call(&mut c, "glTexParameteri", &[tex.clone(), i(GL_TEXTURE_MAX_LEVEL as i64), i(4)]); // GL_TEXTURE_MAX_LEVEL
        assert!(Arc::ptr_eq(&held, &c.shared.textures[&3]));
        // A new value: a new texture with it, the held one as it was.
        call(&mut c, "glTexParameteri", &[tex.clone(), i(0x2803), i(GL_CLAMP_TO_EDGE as i64)]); // WRAP_T CLAMP_TO_EDGE
        let now = &c.shared.textures[&3];
        assert!(!Arc::ptr_eq(&held, now));
        assert_eq!((now.wrap_t, held.wrap_t), (Wrap::ClampToEdge, Wrap::Repeat)); // GL_REPEAT held
        assert_eq!(now.min_filter, Filter::Linear);
        // A texture not made yet takes a value that is not its default.
        call(&mut c, "glBindTexture", &[tex.clone(), i(4)]);
        call(&mut c, "glTexParameteri", &[tex, i(0x2800), i(GL_NEAREST as i64)]); // MAG_FILTER NEAREST
        assert_eq!(c.shared.textures[&4].mag_filter, Filter::Nearest);
    }
    #[test]
    fn a_textures_level_of_detail_bias_and_bounds_are_followed() {
        let mut c = context();
        let tex = i(GL_TEXTURE_2D as i64);
        call(&mut c, "glBindTexture", &[tex.clone(), i(1)]);
        tex_image(&mut c, 0, 2, GL_RGBA as i64, [255; 4]);
        call(&mut c, "glTexParameterf", &[tex.clone(), i(GL_TEXTURE_LOD_BIAS as i64), f(0.25)]); // GL_TEXTURE_LOD_BIAS
        call(&mut c, "glTexParameteri", &[tex.clone(), i(GL_TEXTURE_MAX_LOD as i64), i(3)]); // GL_TEXTURE_MAX_LOD
        let t = c.shared.textures[&1].clone();
        assert_eq!((t.lod.bias, t.lod.min, t.lod.max), (0.25, -1000.0, 3.0));
        // The same value again leaves the same texture.
        call(&mut c, "glTexParameterf", &[tex.clone(), i(0x8501), f(0.25)]);
        assert_eq!(c.shared.textures[&1].version, t.version);
        call(&mut c, "glTexParameterf", &[tex, i(GL_TEXTURE_MIN_LOD as i64), f(-2.0)]); // GL_TEXTURE_MIN_LOD
        assert_eq!(c.shared.textures[&1].lod.min, -2.0);
        assert_ne!(c.shared.textures[&1].version, t.version);
    }
}
