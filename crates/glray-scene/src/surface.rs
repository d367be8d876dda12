//! The per-fragment state of a draw (`Surface`): what the tracer needs of GL besides the
//! triangle to shade a hit as the rasterizer would have: texturing and its environment, fog,
//! the depth and alpha tests, blending, logic ops, clip planes, polygon offset, the colour
//! mask, antialiased coverage.

use std::sync::Arc;

use glam::{DVec4, Vec4};
use serde::{Deserialize, Serialize};

use crate::gl_enum::gl_enum;
use crate::texture::Texture;

gl_enum! {
    /// glFog's GL_FOG_MODE.
    pub enum FogMode {
        Linear = GL_LINEAR,
        Exp = GL_EXP,
        Exp2 = GL_EXP2,
    }
}

gl_enum! {
    /// glTexEnv's GL_TEXTURE_ENV_MODE (GL_COMBINE's stages are not followed: such a draw is
    /// shaded untextured).
    pub enum TexEnvMode {
        Modulate = GL_MODULATE,
        Replace = GL_REPLACE,
        Decal = GL_DECAL,
        Blend = GL_BLEND,
        Add = GL_ADD,
        Combine = GL_COMBINE,
    }
}

gl_enum! {
    /// A comparison of glDepthFunc and glAlphaFunc.
    pub enum CompareFunc {
        Never = GL_NEVER,
        Less = GL_LESS,
        Equal = GL_EQUAL,
        LessOrEqual = GL_LEQUAL,
        Greater = GL_GREATER,
        NotEqual = GL_NOTEQUAL,
        GreaterOrEqual = GL_GEQUAL,
        Always = GL_ALWAYS,
    }
}

impl CompareFunc {
    /// Whether `value` passes the comparison with `reference` (the depth test: a fragment's
    /// depth against the buffer's; the alpha test: its alpha against glAlphaFunc's reference).
    #[inline]
    pub fn passes(self, value: f64, reference: f64) -> bool {
        match self {
            CompareFunc::Never => false,
            CompareFunc::Less => value < reference,
            CompareFunc::Equal => value == reference,
            CompareFunc::LessOrEqual => value <= reference,
            CompareFunc::Greater => value > reference,
            CompareFunc::NotEqual => value != reference,
            CompareFunc::GreaterOrEqual => value >= reference,
            CompareFunc::Always => true,
        }
    }
}

gl_enum! {
    /// A factor of glBlendFunc.
    pub enum BlendFactor {
        Zero = GL_ZERO,
        One = GL_ONE,
        SrcColor = GL_SRC_COLOR,
        OneMinusSrcColor = GL_ONE_MINUS_SRC_COLOR,
        SrcAlpha = GL_SRC_ALPHA,
        OneMinusSrcAlpha = GL_ONE_MINUS_SRC_ALPHA,
        DstAlpha = GL_DST_ALPHA,
        OneMinusDstAlpha = GL_ONE_MINUS_DST_ALPHA,
        DstColor = GL_DST_COLOR,
        OneMinusDstColor = GL_ONE_MINUS_DST_COLOR,
        SrcAlphaSaturate = GL_SRC_ALPHA_SATURATE,
        ConstantColor = GL_CONSTANT_COLOR,
        OneMinusConstantColor = GL_ONE_MINUS_CONSTANT_COLOR,
        ConstantAlpha = GL_CONSTANT_ALPHA,
        OneMinusConstantAlpha = GL_ONE_MINUS_CONSTANT_ALPHA,
    }
}

gl_enum! {
    /// glLogicOp's operation.
    pub enum LogicOp {
        Clear = GL_CLEAR,
        And = GL_AND,
        AndReverse = GL_AND_REVERSE,
        Copy = GL_COPY,
        AndInverted = GL_AND_INVERTED,
        Noop = GL_NOOP,
        Xor = GL_XOR,
        Or = GL_OR,
        Nor = GL_NOR,
        Equiv = GL_EQUIV,
        Invert = GL_INVERT,
        OrReverse = GL_OR_REVERSE,
        CopyInverted = GL_COPY_INVERTED,
        OrInverted = GL_OR_INVERTED,
        Nand = GL_NAND,
        Set = GL_SET,
    }
}

/// glFog state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Fog {
    pub mode: FogMode,
    pub density: f32,
    pub start: f32,
    pub end: f32,
    pub color: Vec4,
}

/// Texturing of a draw: the texture object's image and sampling state, and the environment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Texturing {
    /// Encoded as its version: the byte encoding sends a texture once (`encode`).
    #[serde(with = "crate::objects::shared_texture")]
    pub texture: Arc<Texture>,
    pub env_mode: TexEnvMode,
    pub env_color: Vec4,
}

/// The per-fragment state of a draw: what the tracer needs besides the triangle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Surface {
    pub texturing: Option<Texturing>,
    pub fog: Option<Fog>,
    pub depth_test: bool,
    pub depth_func: CompareFunc,
    pub depth_mask: bool,
    /// (src, dst) factors when GL_BLEND is on.
    pub blend: Option<(BlendFactor, BlendFactor)>,
    /// glLogicOp's operation when GL_COLOR_LOGIC_OP is on (GL then does not blend).
    pub logic_op: Option<LogicOp>,
    /// (func, reference) when GL_ALPHA_TEST is on.
    pub alpha_test: Option<(CompareFunc, f32)>,
    /// Enabled user clip planes (glClipPlane), in eye coordinates: a point is kept where
    /// plane . (x, y, z, 1) >= 0.
    pub clip_planes: Vec<DVec4>,
    /// glPolygonOffset's (factor, units) for the filled polygons of the draw, when
    /// GL_POLYGON_OFFSET_FILL is on (lines and points are not offset).
    pub polygon_offset: Option<(f32, f32)>,
    /// glColorMask: which of red, green, blue and alpha the draw writes (a draw with none
    /// writes only depth, as the first pass of transparent shells does).
    pub color_mask: [bool; 4],
    /// The draw's lines or points are antialiased (GL_LINE_SMOOTH, GL_POINT_SMOOTH): each
    /// fragment's alpha is scaled by how much of its pixel they cover.
    pub coverage: Option<Coverage>,
}

/// How an antialiased line or round point covers the pixels of the quad made for it, half a
/// pixel wider than it on every side (OpenGL 2.1, 3.4.2.2 and 3.3.1): the coverage falls from 1
/// to 0 over the pixel around the edge. The quad's triangles keep the corners in an order that
/// tells its shape: corners 0 and 1 are the ends of a side across the line, 1 to 2 runs along
/// it; a point's corners 0 and 2 are opposite.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Coverage {
    /// A line this many pixels wide.
    Line(f32),
    /// A round point this many pixels across.
    Point(f32),
}

impl Surface {
    /// An opaque, depth-tested (GL_LESS, writing depth) surface with nothing else on: what a
    /// program that only enables GL_DEPTH_TEST draws with.
    pub fn depth_tested() -> Surface {
        Surface {
            texturing: None,
            fog: None,
            depth_test: true,
            depth_func: CompareFunc::Less,
            depth_mask: true,
            blend: None,
            logic_op: None,
            alpha_test: None,
            clip_planes: Vec::new(),
            polygon_offset: None,
            color_mask: [true; 4],
            coverage: None,
        }
    }
}
