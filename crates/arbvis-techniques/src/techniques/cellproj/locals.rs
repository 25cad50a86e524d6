//! The program locals of cell projection's programs (`programs/cellproj/`), named as the
//! programs' comments name them. Each program has its own layout; where a precise program
//! needs the model-view-projection or its inverse, it is in locals 0-3 (`MVP_ROWS`).

/// 0-3: the rows of the model-view-projection (precise isosurfaces), or of its inverse
/// (the volume's grid, peel and walk programs: each pixel's ray).
pub const MVP_ROWS: usize = 0;
/// The view: the eye in object space, w = 1 in perspective (precise isosurfaces, the
/// projected volume); the ARB vertex programs' `D` or `eye`.
pub const EYE: usize = 4;
/// The view direction in object space (precise isosurfaces, the projected volume).
pub const VIEW_DIRECTION: usize = 5;
/// Precise isosurfaces: (isovalue count, lighting on, ambient).
pub const ISOSURFACES: usize = 6;
/// Precise isosurfaces: 7-10, the inverse model-view-projection's rows (each pixel's ray).
pub const INVERSE_MVP: usize = 7;
/// The projected volume: (transfer-function points, 1 / unit distance).
pub const TRANSFER: usize = 6;
/// The faithful volume programs: the pre-integration table's lookup scale and offset
/// (`(sf, sb, length) * scale + offset`),
pub const TABLE_SCALE: usize = 0;
/// ... and offset.
pub const TABLE_OFFSET: usize = 1;
/// The faithful volume per cell (`volume_cell.frag`): the eye (w = 1), or for a parallel
/// view the direction (w = 0).
pub const CELL_EYE: usize = 2;
/// The grid, peel and walk programs: (width, height, the surface's corner x, y) in pixels.
pub const PIXELS: usize = 4;
/// The grid: its low corner.
pub const GRID_LOW: usize = 5;
/// The grid: its points per axis, and the step along the ray.
pub const GRID_DIMS: usize = 6;
/// The grid: the table's sides (sf and sb, length) and the termination.
pub const GRID_TABLE: usize = 7;
/// The grid: 1 / its spacing per axis.
pub const GRID_INVERSE_SPACING: usize = 8;
/// The peel: 1 after the first layer (read the previous layer), else 0.
pub const PEEL_AFTER_FIRST: usize = 5;
/// The walk: (transfer-function points, isovalue count, termination, the eye's
/// tetrahedron or -1).
pub const WALK_TRANSFER: usize = 5;
/// The walk: (layers in this pass, 1 / unit distance, the step limit, 1 after the first
/// pass).
pub const WALK_PASS: usize = 6;
/// The walk: 1 where re-entries are searched (a boundary that is not one convex body).
pub const WALK_SEARCH: usize = 7;
