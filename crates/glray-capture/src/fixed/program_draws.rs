//! Draws made while a GLSL program is in use. A profile that recognises the program
//! (`programs::profile`) says what the draw is in fixed-function terms; the draw is then made as
//! the fixed machine makes a glDrawElements of buffer objects, with that state standing in for
//! the context's own for the one draw: the same meshes (kept while their buffers do not
//! change), instances, lighting and texturing as any other draw. A draw no profile recognises,
//! or one outside the frame's 3D viewport (VTK's orientation axes), is left to the real GL
//! and counted (`Frame::passed_draws`); drawn after the frame's 3D draws, it is drawn over
//! the ray-traced picture (the live layer puts the picture in first: `draw_passes_over`).

use glam::DVec4;
use glray_core::trace::Value;
use glray_scene::lighting::{ColorMaterialMode, LightModel};

use crate::error::GlResult;
use crate::fixed::arrays::ArrayPointer;
use crate::fixed::lighting::LightingState;
use crate::fixed::texturing::TextureUnit;
use crate::fixed::Context;
use crate::ops::Op;
use crate::programs::profile::{Profile, ProgramDraw};
use crate::programs::vertex_arrays::AttribArray;
use crate::programs::vtk::VTK9;

/// The profiles draws are offered to, in order.
pub const PROFILES: &[&Profile] = &[&VTK9];

fn pointer(a: Option<AttribArray>) -> ArrayPointer {
    match a {
        Some(a) => {
            ArrayPointer { enabled: true, size: a.size, ty: a.ty, stride: a.stride, offset: a.offset, buffer: a.buffer }
        }
        None => ArrayPointer::default(),
    }
}

impl Context {
    /// What a draw now would be, if a profile recognises the program in use and the draw is in
    /// the frame's 3D viewport.
    pub(crate) fn recognised_draw(&self) -> Option<ProgramDraw> {
        // The frame's 3D scene is drawn in the viewport its colour clear was made in (VTK's
        // renderer clears its viewport, then draws). Draws elsewhere (the orientation axes'
        // corner, drawn after a clear of the depth alone) stay the real GL's: so does rank 0's
        // axes pass after IceT's compositing, which clears the whole view and draws no scene.
        if self.cleared_viewport.is_some_and(|v| v != self.raster.viewport) {
            return None;
        }
        PROFILES.iter().find_map(|p| p.draw(&self.programs))
    }

    /// Whether a draw made now would be left to the real GL and land over what the frame has
    /// drawn so far (which then has to be in the framebuffer first).
    pub fn draw_passes_over(&self) -> bool {
        self.programmable && !self.frame.is_empty() && self.recognised_draw().is_none()
    }

    /// Why a recognised draw cannot be made yet (its frame is then left to the real GL whole):
    /// translucent (VTK peels depth over several passes into its own framebuffers, which would
    /// put the geometry in the frame several times), or without normals (VTK lights such a
    /// draw, the Glyph filter's arrows, with each facet's normal from screen-space
    /// derivatives).
    pub(crate) fn declined(draw: &ProgramDraw) -> bool {
        draw.material.diffuse.w < 1.0 || draw.inputs.normal.is_none() || draw.peeling
    }

    /// A draw (glDrawArrays, glDrawElements, glDrawRangeElements) while a program is in use.
    pub(crate) fn program_draw(&mut self, op: Op, a: &[Value]) -> GlResult {
        let recognised = self.recognised_draw();
        if recognised.as_ref().is_some_and(Self::declined) {
            self.revision += 1;
            self.frame.unsupported_draws += 1;
            return Ok(());
        }
        let Some(draw) = recognised else {
            if self.core_profile || self.frame.passed_draws > 0 || !self.frame.is_empty() {
                // The real GL draws it; the frame is unchanged (its picture, once put in, stays):
                // the overlays a program draws over its 3D scene.
                self.frame.passed_draws += 1;
                self.passed_total += 1;
            } else {
                // A compatibility context mixing shader draws with fixed-function ones before
                // any is captured: where it lands among them is unknown, so the frame stays the
                // real GL's (said once).
                self.frame.unsupported_draws += 1;
            }
            return Ok(());
        };
        let saved = (
            self.client.clone(),
            self.lighting.clone(),
            self.texturing.clone(),
            *self.matrices.projection.top(),
            *self.matrices.modelview.top(),
            self.imm.current,
            self.normal_matrix,
        );
        self.client.vertex = pointer(Some(draw.inputs.position));
        self.client.normal = pointer(draw.inputs.normal);
        self.client.color = pointer(draw.inputs.color);
        self.client.texcoord = Default::default();
        self.client.texcoord[0] = pointer(draw.inputs.texcoord.filter(|_| draw.color_map.is_some()));
        let mut lighting = LightingState {
            lighting: true,
            model: LightModel {
                ambient: DVec4::new(0.0, 0.0, 0.0, 1.0),
                two_side: true,
                separate_specular: true,
                local_viewer: false,
                per_fragment: draw.per_fragment,
                phong_specular: draw.per_fragment,
            },
            materials: [draw.material; 2],
            normalize: true,
            ..LightingState::default()
        };
        for (slot, light) in lighting.lights.iter_mut().zip(&draw.lights) {
            *slot = *light;
        }
        for slot in lighting.lights.iter_mut().skip(draw.lights.len()) {
            slot.enabled = false;
        }
        if draw.inputs.color.is_some() {
            lighting.color_material = true;
            lighting.color_material_mode = ColorMaterialMode::Diffuse;
        }
        self.lighting = lighting;
        self.texturing = TextureUnit {
            texture_2d: draw.color_map.is_some(),
            bound_texture: draw.color_map.unwrap_or(0),
            ..TextureUnit::default()
        };
        *self.matrices.projection.top_mut() = draw.projection;
        *self.matrices.modelview.top_mut() = draw.modelview;
        self.imm.current.color = DVec4::ONE;
        // VTK blends every draw; an opaque one blends to itself. Drawn without blending, its
        // hits block secondary rays at once instead of each being shaded for its alpha.
        let blend = self.raster.blend;
        self.raster.blend = blend && !self.opaque(&draw);
        if let Some(n) = draw.normal_matrix {
            // The cache the vertex stage and instances read the normal matrix from.
            self.normal_matrix = Some((draw.modelview, n));
        }
        self.programmable = false;
        let result = self.array_command(op, a);
        self.programmable = true;
        let (client, lighting, texturing, projection, modelview, current, normal_matrix) = saved;
        (self.client, self.lighting, self.texturing, self.imm.current) = (client, lighting, texturing, current);
        self.normal_matrix = normal_matrix;
        *self.matrices.projection.top_mut() = projection;
        *self.matrices.modelview.top_mut() = modelview;
        self.raster.blend = blend;
        result
    }

    /// Whether a recognised draw is opaque: its material's opacity is 1, and so is every
    /// colour it maps to (per-vertex colours may carry alpha: not looked at, taken as blended).
    fn opaque(&self, draw: &ProgramDraw) -> bool {
        if draw.material.diffuse.w < 1.0 || draw.inputs.color.is_some() {
            return false;
        }
        match draw.color_map {
            Some(t) => self
                .shared
                .textures
                .get(&t)
                .and_then(|t| t.levels.first())
                .is_some_and(|l| l.texels.iter().all(|c| c.w >= 1.0)),
            None => true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fixed::tests::{call, f32s, i};
    use glam::DMat4;
    use glray_gl::{GL_ARRAY_BUFFER, GL_COLOR_BUFFER_BIT, GL_DEPTH_BUFFER_BIT, GL_FLOAT, GL_TRIANGLES};

    fn returning(c: &mut Context, value: i64, name: &str, args: &[Value]) {
        c.returned = Some(value);
        call(c, name, args);
    }

    fn matrix(c: &mut Context, location: i64, m: DMat4) {
        let bytes = f32s(&m.as_mat4().to_cols_array());
        call(c, "glUniformMatrix4fv", &[i(location), i(1), i(0), Value::Blob(&bytes)]);
    }

    fn vec3(c: &mut Context, location: i64, v: [f32; 3]) {
        call(c, "glUniform3fv", &[i(location), i(1), Value::Blob(&f32s(&v))]);
    }

    /// A core-profile context with VTK's program in use (program 3), a triangle's positions and
    /// normals in buffers 1 and 2, the camera at the origin looking down -z, a white headlight
    /// and a red solid colour, cleared in a 64x64 viewport.
    fn vtk_context() -> (Context, DMat4) {
        let mut c = Context { core_profile: true, ..Context::default() };
        c.set_drawable(64, 64);
        returning(&mut c, 3, "glCreateProgram", &[]);
        for (name, at) in [("vertexMC", 0), ("normalMC", 1)] {
            returning(&mut c, at, "glGetAttribLocation", &[i(3), Value::Str(name.as_bytes())]);
        }
        let uniforms = [
            ("MCDCMatrix", 1),
            ("MCVCMatrix", 2),
            ("OverridesColor", 3),
            ("diffuseIntensity", 5),
            ("opacityUniform", 6),
            ("diffuseColorUniform", 8),
            ("lightColor0", 12),
            ("lightDirectionVC0", 13),
        ];
        for (name, at) in uniforms {
            returning(&mut c, at, "glGetUniformLocation", &[i(3), Value::Str(name.as_bytes())]);
        }
        call(&mut c, "glUseProgram", &[i(3)]);
        let modelview =
            DMat4::from_translation(glam::DVec3::new(0.0, 0.0, -5.0)) * DMat4::from_scale(glam::DVec3::splat(2.0));
        // glFrustum(-0.5, 0.5, -0.5, 0.5, 1, 20).
        let (n, f) = (1.0, 20.0);
        let projection = DMat4::from_cols_array(&[
            2.0 * n,
            0.0,
            0.0,
            0.0,
            0.0,
            2.0 * n,
            0.0,
            0.0,
            0.0,
            0.0,
            -(f + n) / (f - n),
            -1.0,
            0.0,
            0.0,
            -2.0 * f * n / (f - n),
            0.0,
        ]);
        matrix(&mut c, 2, modelview);
        matrix(&mut c, 1, projection * modelview);
        call(&mut c, "glUniform1i", &[i(3), i(1)]);
        call(&mut c, "glUniform1f", &[i(5), Value::F32(1.0)]);
        call(&mut c, "glUniform1f", &[i(6), Value::F32(1.0)]);
        vec3(&mut c, 8, [1.0, 0.0, 0.0]);
        vec3(&mut c, 12, [1.0, 1.0, 1.0]);
        vec3(&mut c, 13, [0.0, 0.0, -1.0]);
        let positions = f32s(&[-0.5, -0.5, 0.0, 0.5, -0.5, 0.0, 0.0, 0.5, 0.0]);
        let normals = f32s(&[0.0, 0.0, 1.0].repeat(3));
        for (buffer, at, data) in [(1, 0, &positions), (2, 1, &normals)] {
            call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(buffer)]);
            call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(36), Value::Blob(data), i(0x88E4)]);
            call(&mut c, "glVertexAttribPointer", &[i(at), i(3), i(GL_FLOAT as i64), i(0), i(12), Value::Offset(0)]);
            call(&mut c, "glEnableVertexAttribArray", &[i(at)]);
        }
        call(&mut c, "glViewport", &[i(0), i(0), i(64), i(64)]);
        call(&mut c, "glClear", &[i((GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT) as i64)]);
        (c, projection)
    }

    #[test]
    fn a_vtk_draw_becomes_a_lit_mesh_seen_through_vtks_camera() {
        let (mut c, projection) = vtk_context();
        assert!(!c.draw_passes_over());
        call(&mut c, "glDrawArrays", &[i(GL_TRIANGLES as i64), i(0), i(3)]);
        let frame = c.frame();
        assert_eq!((frame.triangle_count(), frame.passed_draws), (1, 0));
        let seen = frame.projection.unwrap();
        assert!(seen.abs_diff_eq(projection, 1e-5), "projection = MCDC * inverse(MCVC): {seen}");
        let tri = frame.all_triangles()[0];
        assert!((tri.positions[0].z - -5.0).abs() < 1e-5, "eye space is MCVC * vertexMC: {:?}", tri.positions);
        let lighting = &frame.lightings[0];
        assert!(lighting.model().per_fragment, "VTK lights per fragment");
        assert_eq!(lighting.lights().len(), 1);
        assert_eq!(lighting.lights()[0].position, glam::DVec4::new(0.0, 0.0, 1.0, 0.0), "from where the light comes");
        // A red surface facing the headlight: lit full red.
        assert!((tri.colors[0] - glam::Vec4::new(1.0, 0.0, 0.0, 1.0)).length() < 1e-5, "{:?}", tri.colors[0]);
    }

    #[test]
    fn draws_outside_the_cleared_viewport_or_of_unknown_programs_stay_the_real_gls() {
        let (mut c, _) = vtk_context();
        call(&mut c, "glDrawArrays", &[i(GL_TRIANGLES as i64), i(0), i(3)]);
        // The orientation axes: their own corner of the view, after a clear of the depth alone.
        call(&mut c, "glViewport", &[i(0), i(0), i(16), i(16)]);
        let revision = c.revision();
        call(&mut c, "glClear", &[i(GL_DEPTH_BUFFER_BIT as i64)]);
        assert!(c.draw_passes_over(), "the picture goes in before the axes are drawn over it");
        call(&mut c, "glDrawArrays", &[i(GL_TRIANGLES as i64), i(0), i(3)]);
        assert_eq!((c.frame().triangle_count(), c.frame().passed_draws), (1, 1));
        assert_eq!(c.revision(), revision, "the frame put in is not traced again for them");
        // A program no profile knows (FXAA's full-screen strip).
        call(&mut c, "glViewport", &[i(0), i(0), i(64), i(64)]);
        returning(&mut c, 4, "glCreateProgram", &[]);
        returning(&mut c, 0, "glGetAttribLocation", &[i(4), Value::Str(b"ndCoordIn")]);
        call(&mut c, "glUseProgram", &[i(4)]);
        call(&mut c, "glDrawArrays", &[i(GL_TRIANGLES as i64), i(0), i(3)]);
        assert_eq!(c.frame().passed_draws, 2);
        assert_eq!(c.frame().unsupported_draws, 0, "the frame is still ray traced");
        // In a compatibility context, the same draw before anything is captured: where it lands
        // among the fixed-function draws to come is unknown, so the frame is the real GL's.
        let mut c = Context::default();
        c.set_drawable(64, 64);
        returning(&mut c, 4, "glCreateProgram", &[]);
        returning(&mut c, 0, "glGetAttribLocation", &[i(4), Value::Str(b"ndCoordIn")]);
        call(&mut c, "glUseProgram", &[i(4)]);
        call(&mut c, "glClear", &[i(GL_COLOR_BUFFER_BIT as i64)]);
        call(&mut c, "glDrawArrays", &[i(GL_TRIANGLES as i64), i(0), i(3)]);
        assert_eq!((c.frame().passed_draws, c.frame().unsupported_draws), (0, 1));
    }

    #[test]
    fn instanced_and_base_vertex_draws_leave_the_frame_to_the_real_gl() {
        // Not made into meshes yet (docs/compatibility.md): each such draw marks the frame, so
        // the real GL draws it whole.
        let draws: [(&str, Vec<Value>); 4] = [
            ("glDrawElementsBaseVertex", vec![i(GL_TRIANGLES as i64), i(3), i(0x1405), i(0), i(7)]),
            ("glDrawRangeElementsBaseVertex", vec![i(GL_TRIANGLES as i64), i(0), i(2), i(3), i(0x1405), i(0), i(7)]),
            ("glDrawElementsInstanced", vec![i(GL_TRIANGLES as i64), i(3), i(0x1405), i(0), i(5)]),
            ("glDrawArraysInstancedARB", vec![i(GL_TRIANGLES as i64), i(0), i(3), i(5)]),
        ];
        for (name, args) in draws {
            let (mut c, _) = vtk_context();
            call(&mut c, "glDrawArrays", &[i(GL_TRIANGLES as i64), i(0), i(3)]);
            assert_eq!(c.frame().unsupported_draws, 0, "{name}: a plain draw first");
            call(&mut c, name, &args);
            assert_eq!(c.frame().unsupported_draws, 1, "{name}");
        }
    }

    #[test]
    fn the_programs_own_normal_matrix_is_used() {
        // VTK scales positions per axis into its buffers, not normals: its normal matrix is
        // the rotation alone, where the modelview's inverse transpose would skew the normals.
        let (mut c, _) = vtk_context();
        returning(&mut c, 0, "glGetUniformLocation", &[i(3), Value::Str(b"normalMatrix")]);
        let mv = DMat4::from_translation(glam::DVec3::new(0.0, 0.0, -5.0))
            * DMat4::from_scale(glam::DVec3::new(1.0, 4.0, 1.0));
        matrix(&mut c, 2, mv);
        let rotation = f32s(&glam::Mat3::IDENTITY.to_cols_array());
        call(&mut c, "glUniformMatrix3fv", &[i(0), i(1), i(0), Value::Blob(&rotation)]);
        let normals = f32s(&[0.0, 0.6, 0.8].repeat(3));
        call(&mut c, "glBindBuffer", &[i(GL_ARRAY_BUFFER as i64), i(2)]);
        call(&mut c, "glBufferData", &[i(GL_ARRAY_BUFFER as i64), i(36), Value::Blob(&normals), i(0x88E4)]);
        call(&mut c, "glDrawArrays", &[i(GL_TRIANGLES as i64), i(0), i(3)]);
        let n = c.frame().all_triangles()[0].normals[0];
        assert!((n - glam::Vec3::new(0.0, 0.6, 0.8)).length() < 1e-5, "{n:?}");
        assert!(c.normal_matrix.is_none_or(|(m, _)| m != mv), "the fixed path's cache is its own again");
    }
}
