//! One fixed-function scene, drawn the ways old programs draw: immediate mode with normals, a
//! display list called twice, client vertex arrays, a textured quad, and (where the caller
//! passes them) buffer objects fetched through GetProcAddress; one light, specular material.
//! Deterministic for a given frame number. `Parts` picks which of them are drawn (the trace
//! suite records each part alone).
#![allow(dead_code)]

use super::gl::*;
use glray_gl::{
    GL_AMBIENT_AND_DIFFUSE, GL_ARRAY_BUFFER, GL_COLOR_ARRAY, GL_COLOR_BUFFER_BIT, GL_COLOR_MATERIAL, GL_COMPILE,
    GL_DEPTH_BUFFER_BIT, GL_DEPTH_TEST, GL_FLOAT, GL_FRONT_AND_BACK, GL_LIGHT0, GL_LIGHTING, GL_MAP_WRITE_BIT,
    GL_MODELVIEW, GL_MODULATE, GL_NEAREST, GL_NORMALIZE, GL_PACK_ALIGNMENT, GL_POSITION, GL_PROJECTION, GL_QUADS,
    GL_QUAD_STRIP, GL_RGB, GL_SHININESS, GL_SPECULAR, GL_STATIC_DRAW, GL_TEXTURE_2D, GL_TEXTURE_ENV,
    GL_TEXTURE_ENV_MODE, GL_TEXTURE_MAG_FILTER, GL_TEXTURE_MIN_FILTER, GL_TRIANGLES, GL_TRIANGLE_FAN,
    GL_UNPACK_ALIGNMENT, GL_UNSIGNED_BYTE, GL_UNSIGNED_SHORT, GL_VERTEX_ARRAY,
};
use std::ffi::c_void;

/// Buffer-object entry points, fetched at run time as GLEW and VTK do.
pub struct BufferFns {
    pub gen: unsafe extern "C" fn(i32, *mut u32),
    pub bind: unsafe extern "C" fn(u32, u32),
    pub data: unsafe extern "C" fn(u32, isize, *const c_void, u32),
    pub map_range: unsafe extern "C" fn(u32, isize, isize, u32) -> *mut c_void,
    pub unmap: unsafe extern "C" fn(u32) -> u8,
    pub multi_draw_elements: unsafe extern "C" fn(u32, *const i32, u32, *const *const c_void, i32),
}

impl BufferFns {
    /// Looks the functions up with `get_proc`; None if any is missing.
    pub unsafe fn load(get_proc: impl Fn(&std::ffi::CStr) -> *const c_void) -> Option<BufferFns> {
        let g = get_proc(c"glGenBuffers");
        let b = get_proc(c"glBindBuffer");
        let d = get_proc(c"glBufferData");
        let m = get_proc(c"glMapBufferRange");
        let u = get_proc(c"glUnmapBuffer");
        let md = get_proc(c"glMultiDrawElements");
        if [g, b, d, m, u, md].iter().any(|p| p.is_null()) {
            return None;
        }
        Some(BufferFns {
            gen: std::mem::transmute::<*const c_void, unsafe extern "C" fn(i32, *mut u32)>(g),
            bind: std::mem::transmute::<*const c_void, unsafe extern "C" fn(u32, u32)>(b),
            data: std::mem::transmute::<*const c_void, unsafe extern "C" fn(u32, isize, *const c_void, u32)>(d),
            map_range: std::mem::transmute::<*const c_void, unsafe extern "C" fn(u32, isize, isize, u32) -> *mut c_void>(
                m,
            ),
            unmap: std::mem::transmute::<*const c_void, unsafe extern "C" fn(u32) -> u8>(u),
            multi_draw_elements: std::mem::transmute::<
                *const c_void,
                unsafe extern "C" fn(u32, *const i32, u32, *const *const c_void, i32),
            >(md),
        })
    }
}

/// Which parts of the scene are drawn.
#[derive(Clone, Copy)]
pub struct Parts {
    pub lists: bool,
    pub immediate: bool,
    pub arrays: bool,
    pub buffers: bool,
    pub textures: bool,
}

impl Parts {
    pub const ALL: Parts = Parts { lists: true, immediate: true, arrays: true, buffers: true, textures: true };

    /// From a comma-separated list of part names, or "all".
    pub fn parse(list: &str) -> Result<Parts, String> {
        if list == "all" {
            return Ok(Parts::ALL);
        }
        let mut p = Parts { lists: false, immediate: false, arrays: false, buffers: false, textures: false };
        for name in list.split(',') {
            match name {
                "lists" => p.lists = true,
                "immediate" => p.immediate = true,
                "arrays" => p.arrays = true,
                "buffers" => p.buffers = true,
                "textures" => p.textures = true,
                other => {
                    return Err(format!("unknown part {other:?} (lists, immediate, arrays, buffers, textures, all)"))
                }
            }
        }
        Ok(p)
    }
}

pub struct Scene {
    cube: u32,
    vbo: Option<(u32, &'static BufferFns)>,
    texture: u32,
    parts: Parts,
}

unsafe fn cube_faces() {
    const FACES: [([f32; 3], [[f32; 3]; 4]); 6] = [
        ([0., 0., 1.], [[-1., -1., 1.], [1., -1., 1.], [1., 1., 1.], [-1., 1., 1.]]),
        ([0., 0., -1.], [[-1., -1., -1.], [-1., 1., -1.], [1., 1., -1.], [1., -1., -1.]]),
        ([0., 1., 0.], [[-1., 1., -1.], [-1., 1., 1.], [1., 1., 1.], [1., 1., -1.]]),
        ([0., -1., 0.], [[-1., -1., -1.], [1., -1., -1.], [1., -1., 1.], [-1., -1., 1.]]),
        ([1., 0., 0.], [[1., -1., -1.], [1., 1., -1.], [1., 1., 1.], [1., -1., 1.]]),
        ([-1., 0., 0.], [[-1., -1., -1.], [-1., -1., 1.], [-1., 1., 1.], [-1., 1., -1.]]),
    ];
    glBegin(GL_QUADS);
    for (n, vs) in FACES {
        glNormal3f(n[0], n[1], n[2]);
        for v in vs {
            glVertex3f(v[0], v[1], v[2]);
        }
    }
    glEnd();
}

impl Scene {
    pub unsafe fn new(buffers: Option<&'static BufferFns>) -> Scene {
        Scene::with_parts(buffers, Parts::ALL)
    }

    pub unsafe fn with_parts(buffers: Option<&'static BufferFns>, parts: Parts) -> Scene {
        let cube = glGenLists(1);
        glNewList(cube, GL_COMPILE);
        cube_faces();
        glEndList();
        let vbo = buffers.map(|b| {
            // Allocated empty, filled through a mapping (as VTK does): tests that recording
            // keeps what a program writes into mapped memory.
            let tri: [f32; 9] = [-0.5, -0.4, 0.0, 0.5, -0.4, 0.0, 0.0, 0.5, 0.0];
            let bytes = std::mem::size_of_val(&tri);
            let mut id = 0;
            (b.gen)(1, &mut id);
            (b.bind)(GL_ARRAY_BUFFER, id);
            (b.data)(GL_ARRAY_BUFFER, bytes as isize, std::ptr::null(), GL_STATIC_DRAW);
            let p = (b.map_range)(GL_ARRAY_BUFFER, 0, bytes as isize, GL_MAP_WRITE_BIT);
            if !p.is_null() {
                std::ptr::copy_nonoverlapping(tri.as_ptr().cast::<u8>(), p.cast::<u8>(), bytes);
            }
            (b.unmap)(GL_ARRAY_BUFFER);
            (b.bind)(GL_ARRAY_BUFFER, 0);
            (id, b)
        });
        // An 8x8 RGB checkerboard, rows packed (alignment 1).
        let mut texels = Vec::with_capacity(8 * 8 * 3);
        for y in 0..8 {
            for x in 0..8 {
                texels.extend_from_slice(if (x + y) % 2 == 0 { &[240u8, 240, 240] } else { &[40u8, 90, 200] });
            }
        }
        let mut texture = 0;
        glGenTextures(1, &mut texture);
        glBindTexture(GL_TEXTURE_2D, texture);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB as i32, 8, 8, 0, GL_RGB, GL_UNSIGNED_BYTE, texels.as_ptr().cast());
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST as i32);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST as i32);
        glBindTexture(GL_TEXTURE_2D, 0);
        Scene { cube, vbo, texture, parts }
    }

    pub unsafe fn draw(&self, width: i32, height: i32, frame: u32) {
        glViewport(0, 0, width, height);
        glClearColor(0.1, 0.15, 0.25, 1.0);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        glEnable(GL_DEPTH_TEST);
        glMatrixMode(GL_PROJECTION);
        glLoadIdentity();
        let aspect = width as f64 / height as f64;
        glFrustum(-aspect * 0.5, aspect * 0.5, -0.5, 0.5, 1.0, 30.0);
        glMatrixMode(GL_MODELVIEW);
        glLoadIdentity();
        glTranslatef(0.0, 0.0, -8.0);

        let light = [0.4f32, 0.7, 1.0, 0.0];
        glLightfv(GL_LIGHT0, GL_POSITION, light.as_ptr());
        glEnable(GL_LIGHTING);
        glEnable(GL_LIGHT0);
        glEnable(GL_NORMALIZE);
        glEnable(GL_COLOR_MATERIAL);
        glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
        let white = [0.8f32, 0.8, 0.8, 1.0];
        glMaterialfv(GL_FRONT_AND_BACK, GL_SPECULAR, white.as_ptr());
        glMaterialf(GL_FRONT_AND_BACK, GL_SHININESS, 24.0);
        let p = self.parts;

        // The display list, twice, at different transforms.
        for (i, color) in [[0.9f32, 0.3, 0.2], [0.2, 0.8, 0.3]].iter().enumerate().filter(|_| p.lists) {
            glPushMatrix();
            glTranslatef(if i == 0 { -1.6 } else { 1.6 }, 0.6, 0.0);
            glRotatef(30.0 + 7.0 * frame as f32, 1.0, 1.0, 0.0);
            glScalef(0.8, 0.8, 0.8);
            glColor3f(color[0], color[1], color[2]);
            glCallList(self.cube);
            glPopMatrix();
        }

        // Immediate mode: a lit band of quads.
        if p.immediate {
            glPushMatrix();
            glTranslatef(0.0, -1.4, 0.0);
            glRotatef(-60.0, 1.0, 0.0, 0.0);
            glColor3f(0.9, 0.8, 0.3);
            glBegin(GL_QUAD_STRIP);
            for k in 0..=24 {
                let a = k as f32 / 24.0 * std::f32::consts::TAU;
                glNormal3f(a.cos(), a.sin(), 0.3);
                glVertex3f(2.0 * a.cos(), 2.0 * a.sin(), -0.2);
                glVertex3f(2.2 * a.cos(), 2.2 * a.sin(), 0.2);
            }
            glEnd();
            glPopMatrix();
        }

        // A textured quad, lit, modulated by the material colour.
        if p.textures {
            glPushMatrix();
            glTranslatef(1.9, -1.6, 1.0);
            glRotatef(-25.0, 0.0, 1.0, 0.0);
            glEnable(GL_TEXTURE_2D);
            glBindTexture(GL_TEXTURE_2D, self.texture);
            glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_MODULATE as i32);
            glColor3f(1.0, 1.0, 1.0);
            glBegin(GL_QUADS);
            glNormal3f(0.0, 0.0, 1.0);
            for (s, t) in [(0.0f32, 0.0f32), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)] {
                glTexCoord2f(s, t);
                glVertex3f(s * 0.5 - 0.5, t * 0.5 - 0.5, 0.0);
            }
            glEnd();
            glBindTexture(GL_TEXTURE_2D, 0);
            glDisable(GL_TEXTURE_2D);
            glPopMatrix();
        }

        // Client arrays, unlit, per-vertex colour.
        glDisable(GL_LIGHTING);
        let verts: [f32; 12] = [0.0, 0.0, 0.0, 0.6, 0.0, 0.0, 0.6, 0.6, 0.0, 0.0, 0.6, 0.0];
        let colors: [f32; 12] = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0];
        glPushMatrix();
        glTranslatef(-0.3, 1.6, 0.5);
        glEnableClientState(GL_VERTEX_ARRAY);
        if p.arrays {
            glEnableClientState(GL_COLOR_ARRAY);
            glVertexPointer(3, GL_FLOAT, 0, verts.as_ptr().cast());
            glColorPointer(3, GL_FLOAT, 0, colors.as_ptr().cast());
            glDrawArrays(GL_TRIANGLE_FAN, 0, 4);
            // The same arrays, one element at a time inside glBegin/glEnd.
            glTranslatef(0.8, 0.0, 0.0);
            glBegin(GL_TRIANGLES);
            for k in [1, 2, 3] {
                glArrayElement(k);
            }
            glEnd();
            // Two draws of the same arrays in one call (GL 1.4, fetched like the buffer calls).
            if let Some((_, b)) = self.vbo {
                glTranslatef(0.0, -0.8, 0.0);
                let (first, second) = ([0u16, 1, 2], [0u16, 2, 3]);
                let counts = [3i32, 3];
                let indices = [first.as_ptr().cast::<c_void>(), second.as_ptr().cast::<c_void>()];
                (b.multi_draw_elements)(GL_TRIANGLES, counts.as_ptr(), GL_UNSIGNED_SHORT, indices.as_ptr(), 2);
                glTranslatef(0.0, 0.8, 0.0);
            }
            glTranslatef(-0.8, 0.0, 0.0);
            glDisableClientState(GL_COLOR_ARRAY);
        }

        // A buffer object, if the caller fetched the entry points.
        if let Some((id, b)) = self.vbo.filter(|_| p.buffers) {
            glTranslatef(0.3, -3.4, 0.5);
            glColor3f(0.7, 0.7, 1.0);
            (b.bind)(GL_ARRAY_BUFFER, id);
            glVertexPointer(3, GL_FLOAT, 0, std::ptr::null());
            glDrawArrays(GL_TRIANGLES, 0, 3);
            (b.bind)(GL_ARRAY_BUFFER, 0);
        }
        glDisableClientState(GL_VERTEX_ARRAY);
        glPopMatrix();
    }
}

/// Draws `frames` frames, calling `end_frame` after each (a swap); returns the last frame's
/// pixels, read back before its swap (what the program shows).
pub unsafe fn draw_frames(s: &Scene, width: i32, height: i32, frames: u32, end_frame: impl Fn()) -> Vec<u8> {
    let mut last = Vec::new();
    for frame in 0..frames {
        s.draw(width, height, frame);
        if frame + 1 == frames {
            last = read_rgb(width, height);
        }
        end_frame();
    }
    last
}

/// Reads the current framebuffer (RGB, bottom-up as GL returns it).
pub unsafe fn read_rgb(width: i32, height: i32) -> Vec<u8> {
    let mut pixels = vec![0u8; (width * height * 3) as usize];
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, pixels.as_mut_ptr().cast());
    pixels
}

/// Writes bottom-up RGB rows as a top-down PNG.
pub fn write_png(path: &str, width: u32, height: u32, bottom_up_rgb: &[u8]) -> std::io::Result<()> {
    let row = width as usize * 3;
    let mut top_down = Vec::with_capacity(bottom_up_rgb.len());
    for y in (0..height as usize).rev() {
        top_down.extend_from_slice(&bottom_up_rgb[y * row..(y + 1) * row]);
    }
    let file = std::io::BufWriter::new(std::fs::File::create(path)?);
    let mut enc = png::Encoder::new(file, width, height);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()?.write_image_data(&top_down)?;
    Ok(())
}

/// `PROGRAM OUT.png [FRAMES [PARTS]]` from the command line.
pub fn args() -> (String, u32) {
    let (out, frames, _) = args_with_parts();
    (out, frames)
}

/// `PROGRAM OUT.png [FRAMES [PARTS]]`, PARTS a comma-separated list (see `Parts`).
pub fn args_with_parts() -> (String, u32, Parts) {
    let mut a = std::env::args().skip(1);
    let usage = || -> ! {
        eprintln!("usage: {} OUT.png [FRAMES [PARTS]]", std::env::args().next().unwrap_or_default());
        std::process::exit(2)
    };
    let out = a.next().unwrap_or_else(|| usage());
    let frames = a.next().map(|f| f.parse().unwrap_or_else(|_| usage())).unwrap_or(3);
    let parts = a.next().map(|p| {
        Parts::parse(&p).unwrap_or_else(|e| {
            eprintln!("{e}");
            usage()
        })
    });
    (out, frames, parts.unwrap_or(Parts::ALL))
}
