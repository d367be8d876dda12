//! The GL enums capture reads (from the OpenGL 2.1 headers), in one place; the live layer's
//! replay of a list's state into the real GL (src/raytrace/lists.rs) takes them from here too.
#![allow(dead_code)]

// Enable caps.
pub const GL_LIGHTING: u32 = 0x0B50;
pub const GL_LIGHT0: u32 = 0x4000;
pub const GL_COLOR_MATERIAL: u32 = 0x0B57;
pub const GL_NORMALIZE: u32 = 0x0BA1;
pub const GL_RESCALE_NORMAL: u32 = 0x803A;
pub const GL_CULL_FACE: u32 = 0x0B44;
pub const GL_POLYGON_OFFSET_FILL: u32 = 0x8037;
pub const GL_POINT_SMOOTH: u32 = 0x0B10;
pub const GL_LINE_SMOOTH: u32 = 0x0B20;
pub const GL_DEPTH_TEST: u32 = 0x0B71;
pub const GL_TEXTURE_1D: u32 = 0x0DE0;
pub const GL_COLOR_LOGIC_OP: u32 = 0x0BF2;
pub const GL_COPY: u32 = 0x1503;
pub const GL_TEXTURE_2D: u32 = 0x0DE1;
pub const GL_FOG: u32 = 0x0B60;
pub const GL_BLEND: u32 = 0x0BE2;
pub const GL_ALPHA_TEST: u32 = 0x0BC0;
pub const GL_TEXTURE_GEN_S: u32 = 0x0C60;
pub const GL_TEXTURE_GEN_T: u32 = 0x0C61;
pub const GL_CLIP_PLANE0: u32 = 0x3000;
// Faces and modes.
pub const GL_FRONT: u32 = 0x0404;
pub const GL_BACK: u32 = 0x0405;
pub const GL_FRONT_AND_BACK: u32 = 0x0408;
pub const GL_CW: u32 = 0x0900;
pub const GL_CCW: u32 = 0x0901;
pub const GL_FLAT: u32 = 0x1D00;
pub const GL_SMOOTH: u32 = 0x1D01;
pub const GL_POINT: u32 = 0x1B00;
pub const GL_LINE: u32 = 0x1B01;
pub const GL_FILL: u32 = 0x1B02;
pub const GL_LESS: u32 = 0x0201;
pub const GL_ALWAYS: u32 = 0x0207;
// Material and light parameters.
pub const GL_AMBIENT: u32 = 0x1200;
pub const GL_DIFFUSE: u32 = 0x1201;
pub const GL_SPECULAR: u32 = 0x1202;
pub const GL_POSITION: u32 = 0x1203;
pub const GL_SPOT_DIRECTION: u32 = 0x1204;
pub const GL_SPOT_EXPONENT: u32 = 0x1205;
pub const GL_SPOT_CUTOFF: u32 = 0x1206;
pub const GL_CONSTANT_ATTENUATION: u32 = 0x1207;
pub const GL_LINEAR_ATTENUATION: u32 = 0x1208;
pub const GL_QUADRATIC_ATTENUATION: u32 = 0x1209;
pub const GL_EMISSION: u32 = 0x1600;
pub const GL_SHININESS: u32 = 0x1601;
pub const GL_AMBIENT_AND_DIFFUSE: u32 = 0x1602;
pub const GL_LIGHT_MODEL_LOCAL_VIEWER: u32 = 0x0B51;
pub const GL_LIGHT_MODEL_TWO_SIDE: u32 = 0x0B52;
pub const GL_LIGHT_MODEL_AMBIENT: u32 = 0x0B53;
pub const GL_LIGHT_MODEL_COLOR_CONTROL: u32 = 0x81F8;
pub const GL_SEPARATE_SPECULAR_COLOR: u32 = 0x81FA;
pub const GL_SINGLE_COLOR: u32 = 0x81F9;
// Client arrays.
pub const GL_VERTEX_ARRAY: u32 = 0x8074;
pub const GL_NORMAL_ARRAY: u32 = 0x8075;
pub const GL_COLOR_ARRAY: u32 = 0x8076;
pub const GL_TEXTURE_COORD_ARRAY: u32 = 0x8078;
pub const GL_ARRAY_BUFFER: u32 = 0x8892;
pub const GL_ELEMENT_ARRAY_BUFFER: u32 = 0x8893;
// Textures, fog, pixel store.
pub const GL_TEXTURE_MIN_FILTER: u32 = 0x2801;
pub const GL_TEXTURE_MAG_FILTER: u32 = 0x2800;
pub const GL_TEXTURE_WRAP_S: u32 = 0x2802;
pub const GL_TEXTURE_WRAP_T: u32 = 0x2803;
pub const GL_TEXTURE_ENV_MODE: u32 = 0x2200;
pub const GL_TEXTURE_ENV_COLOR: u32 = 0x2201;
pub const GL_MODULATE: u32 = 0x2100;
pub const GL_TEXTURE_GEN_MODE: u32 = 0x2500;
pub const GL_OBJECT_PLANE: u32 = 0x2501;
pub const GL_EYE_PLANE: u32 = 0x2502;
pub const GL_OBJECT_LINEAR: u32 = 0x2401;
pub const GL_EYE_LINEAR: u32 = 0x2400;
pub const GL_SPHERE_MAP: u32 = 0x2402;
pub const GL_S: u32 = 0x2000;
pub const GL_T: u32 = 0x2001;
pub const GL_FOG_MODE: u32 = 0x0B65;
pub const GL_FOG_DENSITY: u32 = 0x0B62;
pub const GL_FOG_START: u32 = 0x0B63;
pub const GL_FOG_END: u32 = 0x0B64;
pub const GL_FOG_COLOR: u32 = 0x0B66;
pub const GL_EXP: u32 = 0x0800;
pub const GL_UNPACK_ROW_LENGTH: u32 = 0x0CF2;
pub const GL_UNPACK_SKIP_ROWS: u32 = 0x0CF3;
pub const GL_UNPACK_SKIP_PIXELS: u32 = 0x0CF4;
pub const GL_UNPACK_ALIGNMENT: u32 = 0x0CF5;
pub const GL_TEXTURE0: u32 = 0x84C0;
// glClear and glPushAttrib bits.
pub const GL_COLOR_BUFFER_BIT: u32 = 0x4000;
pub const GL_CURRENT_BIT: u32 = 0x0001;
pub const GL_POINT_BIT: u32 = 0x0002;
pub const GL_LINE_BIT: u32 = 0x0004;
pub const GL_POLYGON_BIT: u32 = 0x0008;
pub const GL_LIGHTING_BIT: u32 = 0x0040;
pub const GL_FOG_BIT: u32 = 0x0080;
pub const GL_DEPTH_BUFFER_BIT: u32 = 0x0100;
pub const GL_VIEWPORT_BIT: u32 = 0x0800;
pub const GL_TRANSFORM_BIT: u32 = 0x1000;
pub const GL_ENABLE_BIT: u32 = 0x2000;
pub const GL_SCISSOR_BIT: u32 = 0x0008_0000;
pub const GL_SCISSOR_TEST: u32 = 0x0C11;
pub const GL_TEXTURE_BIT: u32 = 0x40000;
pub const MAX_ATTRIB_DEPTH: usize = 16;

// Matrix state the live layer reads back from the real GL.
pub const GL_MATRIX_MODE: u32 = 0x0BA0;
pub const GL_MODELVIEW: u32 = 0x1700;
pub const GL_MODELVIEW_MATRIX: u32 = 0x0BA6;
