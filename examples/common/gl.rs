//! The GL 1.x entry points the examples call, declared as a C program's GL/gl.h would. Which
//! library provides them is chosen by each example's #[link] (libGL or libOSMesa).
#![allow(dead_code, non_snake_case)]

use std::ffi::c_void;

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
