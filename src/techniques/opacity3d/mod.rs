//! v3o2's 3D opacity (seed `000_7bcb64b2a3c67198.txt`): three attribute volumes packed in
//! one RGB 3D texture (G primary, B secondary, R tertiary) on unit 0, colour tables on
//! units 2/3/4, twelve coefficients in `program.local[1..3]`, combined by the verbatim
//! sum or product `!!ARBfp1.0` program, drawn as view-aligned slices back to front.
//!
//! Built so far: [`slicing`], the CPU geometry of the view-aligned slices. The renderer,
//! data loaders, CPU reference and editor are the rest of the technique's issue.

pub mod slicing;
