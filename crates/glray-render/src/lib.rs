//! glray's ray tracer (DESIGN.md: "engine"): turns a captured `Frame` into pixels.
//!
//! - `scene`: the frame's geometry and its BVHs (obvhs), two levels: the frame's own triangles,
//!   and display-list meshes kept across frames under a top level over their instances;
//! - `fragment`: a hit as the rasterizer would have produced it: interpolated colour, texture,
//!   fog, window depth (the GL look);
//! - `resolve`: per pixel, which fragments survive GL's depth test, alpha test and blending,
//!   in drawing order;
//! - `render`: the camera's rays over the image, in rayon row tiles, deterministic.

pub mod fragment;
pub mod render;
pub mod resolve;
pub mod scene;

pub use render::{render, Options, Rendered, Renderer};
