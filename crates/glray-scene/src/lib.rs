//! A frame's scene as data: what capture produces and the tracer consumes, and what crosses MPI
//! ranks. Nothing here knows GL calls or rays through a BVH: the state capture followed, made
//! into typed values (enums, not GL's numbers), and the few evaluations that belong to the
//! scene itself (GL's lighting equation, which face of a triangle is seen, texture sampling,
//! the rays a camera casts), so that the tracer never calls back into capture.
//!
//! - `frame`: a frame: triangles, instances, solids, surfaces, lightings, cameras, clears;
//! - `triangle`: one triangle as the rasterizer would draw it;
//! - `mesh`: object-space triangles with their vertices' attributes, with ids;
//! - `instance`: one draw of a mesh and the state of that draw, whose triangles are made when a
//!   ray needs one;
//! - `surface`: the per-fragment state of a draw (texturing, fog, tests, blending...);
//! - `texture`: texture objects and GL's sampling;
//! - `camera`: rays through pixel centres from a projection and viewport, window depths;
//! - `lighting`: lights, materials, the light model and the fixed-function equation;
//! - `sunlit`: that equation in single precision for lights at infinity;
//! - `draw_lighting`: the lighting state of a lit draw, with what it derives;
//! - `facing`: which face of a triangle is seen, and culling;
//! - `ids`: mesh and texture ids, unique across MPI ranks;
//! - `merge`: the frames of several ranks made one;
//! - `encode`: the versioned byte encoding (meshes and textures sent once, by id);
//! - `objects`: the meshes and textures a receiver holds, by id, and the fields naming them;
//! - `pod_vec`: big arrays encoded as their bytes;
//! - `gl_enum`: typed enums for sets of GL values, with GL's numbers by name.

pub mod camera;
pub mod covered;
pub mod draw_lighting;
pub mod encode;
pub mod facing;
pub mod frame;
mod gl_enum;
pub mod ids;
pub mod instance;
pub mod join;
pub mod lighting;
pub mod merge;
pub mod mesh;
pub mod objects;
mod pod_vec;
pub mod sunlit;
pub mod surface;
pub mod texture;
pub mod triangle;
