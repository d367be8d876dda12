//! The shader-program layer, beside the fixed-function machine (`fixed`): what a context that
//! draws through GLSL programs has set up for its draws, followed from its calls, and what a
//! draw means when a *profile* recognises the program that makes it.
//!
//! - `program`: program objects by their inputs' names (attribute and uniform locations) and
//!   their uniforms' values;
//! - `vertex_arrays`: generic vertex attributes and vertex array objects;
//! - `profile`: a family of programs described as data (the names of its inputs), and what a
//!   draw of one is: meshes' attributes, transforms, lights, material, colour map;
//! - `vtk`: the profile of VTK 9's polygonal-data programs (ParaView 5.11).
//!
//! Buffer objects and textures are the context's (the fixed machine follows them for both
//! kinds of draw); this layer keeps which texture each unit has bound, which a sampler uniform
//! names. A draw no profile recognises is left to the real GL.

pub mod profile;
pub mod program;
pub mod vertex_arrays;
pub mod vtk;

use std::collections::HashMap;

use glray_core::trace::Value;
use glray_gl::{GL_FLOAT, GL_TEXTURE0, GL_TEXTURE_2D};

use crate::args;
use crate::error::{GlError, GlResult};
use crate::ops::Op;
use program::Program;
use vertex_arrays::VertexArrays;

/// How many texture units' bindings are followed.
pub const TEXTURE_UNITS: usize = 32;

/// A context's program state: the program objects (by name), the one in use, the vertex arrays
/// and the 2D texture bound on each unit.
#[derive(Debug, Clone, Default)]
pub struct Programs {
    pub objects: HashMap<u32, Program>,
    pub in_use: u32,
    pub vertex_arrays: VertexArrays,
    /// glActiveTexture's unit.
    pub active_unit: usize,
    /// The 2D texture bound on each unit.
    pub units: HashMap<usize, u32>,
}

impl Programs {
    /// The program in use, if capture knows it.
    pub fn current(&self) -> Option<&Program> {
        self.objects.get(&self.in_use).filter(|_| self.in_use != 0)
    }

    /// The 2D texture bound on `unit`.
    pub fn texture_on(&self, unit: usize) -> u32 {
        self.units.get(&unit).copied().unwrap_or(0)
    }

    /// Follows the binding commands the fixed machine also follows: which program is in use,
    /// the active texture unit and its 2D binding.
    pub fn observe(&mut self, op: Op, a: &[Value]) {
        match op {
            Op::UseProgram => self.in_use = args::uint(a, 0),
            Op::ActiveTexture => {
                let unit = args::uint(a, 0).wrapping_sub(GL_TEXTURE0) as usize;
                if unit < TEXTURE_UNITS {
                    self.active_unit = unit;
                }
            }
            Op::BindTexture if args::uint(a, 0) == GL_TEXTURE_2D => {
                self.units.insert(self.active_unit, args::uint(a, 1));
            }
            _ => {}
        }
    }

    /// Follows a command of the program layer (`Concern::Programs`); `returned` is the call's
    /// return value (a program's name, a location), `array_buffer` the buffer bound to
    /// GL_ARRAY_BUFFER (the context's, which glVertexAttribPointer reads).
    pub fn command(&mut self, op: Op, ty: u32, a: &[Value], returned: Option<i64>, array_buffer: u32) -> GlResult {
        match op {
            Op::CreateProgram => {
                if let Some(name) = returned.filter(|&n| n > 0) {
                    self.objects.insert(name as u32, Program::default());
                }
            }
            Op::DeleteProgram => {
                self.objects.remove(&args::uint(a, 0));
            }
            Op::LinkProgram => {
                if let Some(p) = self.objects.get_mut(&args::uint(a, 0)) {
                    p.linked();
                }
            }
            Op::BindAttribLocation => {
                if let Some(p) = self.objects.get_mut(&args::uint(a, 0)) {
                    p.attribute_located(args::bytes(a, 2), args::int(a, 1));
                }
            }
            Op::GetAttribLocation => {
                if let (Some(p), Some(at)) = (self.objects.get_mut(&args::uint(a, 0)), returned) {
                    p.attribute_located(args::bytes(a, 1), at as i32 as i64);
                }
            }
            Op::GetUniformLocation => {
                if let (Some(p), Some(at)) = (self.objects.get_mut(&args::uint(a, 0)), returned) {
                    p.uniform_located(args::bytes(a, 1), at as i32 as i64);
                }
            }
            Op::Uniform | Op::UniformMatrix => {
                let location = args::int(a, 0) as i32;
                let value = uniform_value(op, ty, a);
                if let Some(p) = self.objects.get_mut(&self.in_use) {
                    p.set_uniform(location, value);
                }
            }
            Op::BindVertexArray => self.vertex_arrays.bind(args::uint(a, 0)),
            Op::DeleteVertexArrays => {
                let names = args::array(args::bytes(a, 1), glray_gl::GL_UNSIGNED_INT, args::int(a, 0).max(0) as usize);
                self.vertex_arrays.delete(names.into_iter().map(|n| n as u32));
            }
            Op::EnableVertexAttrib | Op::DisableVertexAttrib => {
                let on = op == Op::EnableVertexAttrib;
                self.vertex_arrays.attrib_mut(args::uint(a, 0)).ok_or(GlError::InvalidValue)?.enabled = on;
            }
            Op::VertexAttribPointer => {
                // glVertexAttribPointer(index, size, type, normalized, stride, pointer);
                // glVertexAttribIPointer has no `normalized`.
                let integer = a.len() == 5;
                let (ty_at, stride_at, pointer_at) = if integer { (2, 3, 4) } else { (2, 4, 5) };
                let attrib = self.vertex_arrays.attrib_mut(args::uint(a, 0)).ok_or(GlError::InvalidValue)?;
                attrib.size = args::int(a, 1) as i32;
                attrib.ty = args::uint(a, ty_at);
                attrib.normalized = !integer && args::int(a, 3) != 0;
                attrib.stride = args::int(a, stride_at) as i32;
                attrib.offset = a.get(pointer_at).map_or(0, |v| v.as_int() as u64);
                attrib.buffer = array_buffer;
            }
            Op::VertexAttribDivisor => {
                self.vertex_arrays.attrib_mut(args::uint(a, 0)).ok_or(GlError::InvalidValue)?.divisor =
                    args::uint(a, 1);
            }
            _ => unreachable!("{op:?} is not a program command"),
        }
        Ok(())
    }
}

/// A glUniform*'s components: scalars after the location, or the array of the `v` and matrix
/// forms (`count` values, each as many components as the array holds over `count`).
fn uniform_value(op: Op, ty: u32, a: &[Value]) -> Vec<f64> {
    let vector_at = if op == Op::UniformMatrix { 3 } else { 2 };
    match a.get(vector_at) {
        Some(Value::Blob(b)) => {
            let size = args::type_size(ty).unwrap_or(4);
            let mut v = args::array(b, ty, b.len() / size);
            if op == Op::UniformMatrix && args::int(a, 2) != 0 {
                // Given transposed: kept column by column as GL stores it.
                let n = (v.len() as f64).sqrt() as usize;
                if n * n == v.len() {
                    v = (0..n * n).map(|k| v[(k % n) * n + k / n]).collect();
                }
            }
            v
        }
        _ => (1..a.len()).map(|k| if ty == GL_FLOAT { args::float(a, k) } else { args::int(a, k) as f64 }).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::op_for;

    fn call(p: &mut Programs, name: &str, a: &[Value], ret: Option<i64>) {
        let (op, ty) = op_for(name).unwrap();
        p.command(op, ty, a, ret, 9).unwrap();
    }

    #[test]
    fn uniforms_attributes_and_vertex_arrays_are_followed_by_name() {
        let mut p = Programs::default();
        let i = Value::Int;
        call(&mut p, "glCreateProgram", &[], Some(5));
        call(&mut p, "glGetUniformLocation", &[i(5), Value::Str(b"MCVCMatrix")], Some(2));
        call(&mut p, "glGetUniformLocation", &[i(5), Value::Str(b"opacityUniform")], Some(3));
        call(&mut p, "glGetAttribLocation", &[i(5), Value::Str(b"vertexMC")], Some(1));
        p.observe(op_for("glUseProgram").unwrap().0, &[i(5)]);
        let m: Vec<u8> = (0..16).flat_map(|k| (k as f32).to_ne_bytes()).collect();
        call(&mut p, "glUniformMatrix4fv", &[i(2), i(1), i(1), Value::Blob(&m)], None);
        call(&mut p, "glUniform1f", &[i(3), Value::F32(0.5)], None);
        let prog = p.current().unwrap();
        assert_eq!(prog.uniform("opacityUniform"), Some(&[0.5][..]));
        let mcvc = prog.uniform("MCVCMatrix").unwrap();
        assert_eq!((mcvc[1], mcvc[4]), (4.0, 1.0), "a transposed matrix is kept column by column");
        assert_eq!(prog.attribute("vertexMC"), Some(1));
        // (The context's array buffer, 9, is handed to every command.)
        call(&mut p, "glBindVertexArray", &[i(4)], None);
        call(&mut p, "glVertexAttribPointer", &[i(1), i(3), i(GL_FLOAT as i64), i(0), i(24), Value::Offset(12)], None);
        call(&mut p, "glEnableVertexAttribArray", &[i(1)], None);
        let a = p.vertex_arrays.attrib(1).unwrap();
        assert_eq!((a.enabled, a.size, a.stride, a.offset, a.buffer), (true, 3, 24, 12, 9));
    }
}
