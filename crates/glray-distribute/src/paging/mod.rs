//! Paging (`distribute = paged`, the paper's second mode after Ize et al. 2011): each rank
//! keeps the meshes its host drew, cut into blocks with their trees (`blocks`); every rank
//! knows every paged mesh's layout (its blocks' boxes and owners) and fetches the blocks its
//! rays reach from their owners into a bounded cache (`cache`, `pager`). No rank holds the
//! whole scene, nor builds a tree over it.

pub mod blocks;
pub mod cache;
pub mod pager;

pub use pager::{Asks, Budget, Missing, Paging, PagingReport, PagingSetup, Resident};
