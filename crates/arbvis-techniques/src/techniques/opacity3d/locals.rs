//! The program locals of 3D opacity's programs (`programs/opacity3d/`), named as the
//! programs' `PARAM` lines and comments name them. The verbatim programs read only the
//! coefficients; the precise programs (slices and ray caster) the rest. The clip's locals
//! follow from `clip::stage::FIRST_LOCAL` (10; a store, which the paged locals serve,
//! takes no clip).

/// 1, 2, 3: the primary, secondary and tertiary attribute's coefficient vector.
pub const COEFFICIENTS: usize = 1;
/// The opacity correction: (1 / reference length, or 0 where off; the length a sample
/// stands for: half the slice spacing, or the ray's step; 0, or 1 where off; 0).
pub const CORRECTION: usize = 4;
/// Table lookup at texel centres (255/256, 0.5/256) and a sum's exact third (1/3).
pub const LOOKUP: usize = 5;
/// The box's size in object units.
pub const BOX_SIZE: usize = 6;
/// The box's half size.
pub const BOX_HALF: usize = 7;
/// The ray: the eye (perspective), its direction (ray caster, orthographic) or the
/// direction's sign per axis (slices, orthographic).
pub const RAY: usize = 8;
/// Along the ray: the view axis (slices, perspective), 1 / |direction| per axis (slices,
/// orthographic), or bricks per unit and the transmittance where rays stop (ray caster).
pub const AXIS: usize = 9;
/// The paged ray caster: the window's size in voxels, and the brick side.
pub const PAGED_WINDOW: usize = 10;
/// The paged ray caster: the window's first voxel.
pub const PAGED_FIRST_VOXEL: usize = 11;
/// The paged ray caster: 1 / the atlas's texels per axis.
pub const PAGED_PER_TEXEL: usize = 12;
/// The paged ray caster: the page table's first page.
pub const PAGED_FIRST_PAGE: usize = 13;
/// The slices' own trilinear filter (`exact_volume`): the volume's size in voxels.
pub const EXACT_SIZE: usize = 14;
/// The slices' own trilinear filter: 1 / the volume's size.
pub const EXACT_INVERSE_SIZE: usize = 15;
/// A window pixel to normalized device coordinates: the scale,
pub const PIXEL_TO_NDC_SCALE: usize = 16;
/// ... and the offset.
pub const PIXEL_TO_NDC_OFFSET: usize = 17;
/// 18, 19, 20, 21: the rows of the inverse model-view-projection (each pixel's ray).
pub const INVERSE_MVP: usize = 18;
/// The ray caster: the low corner of the box that holds visible voxels,
pub const OCCUPIED_LOW: usize = 22;
/// ... and its high corner.
pub const OCCUPIED_HIGH: usize = 23;
