//! The GL 1.x entry points the examples call, declared as a C program's GL/gl.h would. Which
//! library provides them is chosen by each example's #[link] (libGL or libOSMesa).
#![allow(dead_code, non_snake_case)]

use std::ffi::c_void;

pub const GL_POINTS: u32 = 0x0000;
pub const GL_TRIANGLES: u32 = 0x0004;
pub const GL_TRIANGLE_FAN: u32 = 0x0006;
pub const GL_QUADS: u32 = 0x0007;
pub const GL_QUAD_STRIP: u32 = 0x0008;
pub const GL_COMPILE: u32 = 0x1300;
pub const GL_COLOR_BUFFER_BIT: u32 = 0x4000;
pub const GL_DEPTH_BUFFER_BIT: u32 = 0x0100;
pub const GL_DEPTH_TEST: u32 = 0x0B71;
pub const GL_LIGHTING: u32 = 0x0B50;
pub const GL_LIGHT0: u32 = 0x4000;
pub const GL_POSITION: u32 = 0x1203;
pub const GL_DIFFUSE: u32 = 0x1201;
pub const GL_AMBIENT_AND_DIFFUSE: u32 = 0x1602;
pub const GL_FRONT: u32 = 0x0404;
pub const GL_BACK: u32 = 0x0405;
pub const GL_FRONT_AND_BACK: u32 = 0x0408;
pub const GL_COLOR_MATERIAL: u32 = 0x0B57;
pub const GL_NORMALIZE: u32 = 0x0BA1;
pub const GL_MODELVIEW: u32 = 0x1700;
pub const GL_PROJECTION: u32 = 0x1701;
pub const GL_VERTEX_ARRAY: u32 = 0x8074;
pub const GL_COLOR_ARRAY: u32 = 0x8076;
pub const GL_FLOAT: u32 = 0x1406;
pub const GL_UNSIGNED_SHORT: u32 = 0x1403;
pub const GL_RGB: u32 = 0x1907;
pub const GL_RGBA: u32 = 0x1908;
pub const GL_UNSIGNED_BYTE: u32 = 0x1401;
pub const GL_VIEWPORT: u32 = 0x0BA2;
pub const GL_VERSION: u32 = 0x1F02;
pub const GL_RENDERER: u32 = 0x1F01;
pub const GL_PACK_ALIGNMENT: u32 = 0x0D05;
pub const GL_ARRAY_BUFFER: u32 = 0x8892;
pub const GL_STATIC_DRAW: u32 = 0x88E4;
pub const GL_NO_ERROR: u32 = 0;
pub const GL_SPECULAR: u32 = 0x1202;
pub const GL_SHININESS: u32 = 0x1601;
pub const GL_TEXTURE_2D: u32 = 0x0DE1;
pub const GL_TEXTURE_MIN_FILTER: u32 = 0x2801;
pub const GL_TEXTURE_MAG_FILTER: u32 = 0x2800;
pub const GL_NEAREST: i32 = 0x2600;
pub const GL_LINEAR: i32 = 0x2601;
pub const GL_TEXTURE_ENV: u32 = 0x2300;
pub const GL_TEXTURE_ENV_MODE: u32 = 0x2200;
pub const GL_MODULATE: i32 = 0x2100;
pub const GL_UNPACK_ALIGNMENT: u32 = 0x0CF5;

extern "C" {
    pub fn glClearColor(r: f32, g: f32, b: f32, a: f32);
    pub fn glClear(mask: u32);
    pub fn glEnable(cap: u32);
    pub fn glDisable(cap: u32);
    pub fn glViewport(x: i32, y: i32, w: i32, h: i32);
    pub fn glMatrixMode(mode: u32);
    pub fn glLoadIdentity();
    pub fn glFrustum(l: f64, r: f64, b: f64, t: f64, n: f64, f: f64);
    pub fn glTranslatef(x: f32, y: f32, z: f32);
    pub fn glRotatef(a: f32, x: f32, y: f32, z: f32);
    pub fn glScalef(x: f32, y: f32, z: f32);
    pub fn glPushMatrix();
    pub fn glPopMatrix();
    pub fn glLightfv(light: u32, pname: u32, params: *const f32);
    pub fn glMaterialfv(face: u32, pname: u32, params: *const f32);
    pub fn glColorMaterial(face: u32, mode: u32);
    pub fn glBegin(mode: u32);
    pub fn glEnd();
    pub fn glArrayElement(i: i32);
    pub fn glVertex3f(x: f32, y: f32, z: f32);
    pub fn glNormal3f(x: f32, y: f32, z: f32);
    pub fn glColor3f(r: f32, g: f32, b: f32);
    pub fn glGenLists(n: i32) -> u32;
    pub fn glNewList(list: u32, mode: u32);
    pub fn glEndList();
    pub fn glCallList(list: u32);
    pub fn glDeleteLists(list: u32, n: i32);
    pub fn glEnableClientState(a: u32);
    pub fn glDisableClientState(a: u32);
    pub fn glVertexPointer(size: i32, ty: u32, stride: i32, p: *const c_void);
    pub fn glColorPointer(size: i32, ty: u32, stride: i32, p: *const c_void);
    pub fn glDrawArrays(mode: u32, first: i32, count: i32);
    pub fn glDrawElements(mode: u32, count: i32, ty: u32, indices: *const std::ffi::c_void);
    pub fn glPixelStorei(pname: u32, param: i32);
    pub fn glReadPixels(x: i32, y: i32, w: i32, h: i32, format: u32, ty: u32, data: *mut c_void);
    pub fn glFinish();
    pub fn glGetError() -> u32;
    pub fn glGetIntegerv(pname: u32, data: *mut i32);
    pub fn glGetString(name: u32) -> *const u8;
    pub fn glPushAttrib(mask: u32);
    pub fn glPopAttrib();
    pub fn glGenTextures(n: i32, textures: *mut u32);
    pub fn glBindTexture(target: u32, texture: u32);
    pub fn glTexImage2D(
        target: u32,
        level: i32,
        internal: i32,
        w: i32,
        h: i32,
        border: i32,
        format: u32,
        ty: u32,
        data: *const c_void,
    );
    pub fn glTexParameteri(target: u32, pname: u32, param: i32);
    pub fn glTexEnvi(target: u32, pname: u32, param: i32);
    pub fn glTexCoord2f(s: f32, t: f32);
    pub fn glMaterialf(face: u32, pname: u32, param: f32);
}
