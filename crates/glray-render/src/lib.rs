//! glray's ray tracer (DESIGN.md: "engine"): turns a captured `Frame` into pixels.
//!
//! - `bvh`: glray's own four-wide BVH over triangles (binned SAH build, SIMD traversal);
//! - `meshes`: the BVHs of meshes, kept across frames while the meshes live (refitted for time
//!   steps);
//! - `scene`: one frame's geometry to trace, two levels: the frame's own triangles, and the
//!   kept meshes' trees under a top level (obvhs) over their instances;
//! - `fragment`: a hit as the rasterizer would have produced it: interpolated colour, texture,
//!   fog, window depth (the GL look);
//! - `gouraud`: the short way to shade hits on untextured instances when the frame asks for
//!   the GL look alone (corner colours mixed with the walk's weights);
//! - `resolve`: per pixel, which fragments survive GL's depth test, alpha test and blending,
//!   in drawing order;
//! - `options`: how to render: the effects and their presets, lighting per pixel, BVH builds;
//! - `effects`: ambient occlusion and shadows at a hit;
//! - `denoise`: ambient occlusion kept apart from the colours, averaged over frames through
//!   motion and filtered along surfaces;
//! - `offset`: where a secondary ray leaves a surface;
//! - `recent`: what was made of the triangles recent camera rays hit;
//! - `sampling`: deterministic random numbers (a function of pixel and sample) and directions;
//! - `tracer`: one pixel's samples, resolved as the rasterizer would, with the effects;
//! - `render`: the image in rayon row tiles, deterministic; progressive refinement over frames
//!   that show the same scene (`signature`), statistics, progress on a terminal (`progress`).

pub mod bvh;
pub mod bvh_choice;
pub mod denoise;
pub mod effects;
pub mod fragment;
mod gouraud;
pub mod meshes;
pub mod offset;
pub mod options;
pub mod paged;
mod parking;
pub mod pieces;
mod progress;
mod recent;
pub mod render;
pub mod resolve;
pub mod sampling;
pub mod scene;
mod signature;
mod smooth;
pub mod tiles;
mod top;
mod tracer;

pub use options::{Effects, Options};
pub use render::{render, Rendered, Renderer, Stats};
