//! VTK XML unstructured grids (`.vtu`, `<VTKFile type="UnstructuredGrid">`), one piece.
//!
//! The XML is read with `quick-xml` up to the `<AppendedData>` element, whose raw bytes
//! follow the `_` marker and are never given to the XML parser. Each `DataArray` of
//! `Points`, `Cells` (`connectivity`, `offsets`, `types`), `PointData` and `CellData` is
//! decoded from:
//! - `format="ascii"`: whitespace-separated numbers in the element;
//! - `format="binary"`: base64 in the element, whitespace ignored;
//! - `format="appended"`: at `offset` in the appended data, `encoding="raw"` or `"base64"`.
//!
//! Binary data start with a header of `header_type` integers (`UInt32`, the default, or
//! `UInt64`) in the file's `byte_order`: uncompressed, the byte count; with
//! `compressor="vtkZLibDataCompressor"`, the block count `n`, the uncompressed block size,
//! the size of the last block (0: a full block) and the `n` compressed sizes, followed by
//! the zlib blocks. In base64, VTK encodes the header and the data separately (the header
//! ends in `=` padding); other writers encode them together; both are read. Every
//! declared size is checked before anything is allocated: a block may not declare more
//! than 1032 bytes per compressed byte (the most deflate can produce), and inflation stops
//! one byte past the declared size, which is then an error.
//!
//! Decisions: `offsets` are end offsets (one per cell, VTK XML's convention); arrays in
//! `FieldData` and other elements are not decoded; more than one `<Piece>`, other dataset
//! types and other compressors (LZ4, LZMA) are refused by name. Positions inside base64
//! or compressed data cannot be mapped back to the file: such errors give the position
//! of the `DataArray` tag and the index of the value.

mod assemble;
mod data;
mod desc;
mod scan;

use std::path::Path;

use super::{Mesh, MeshError};

/// Parse a `.vtu` file held in memory; `name` is used in errors.
pub fn parse(name: &Path, bytes: &[u8]) -> Result<Mesh, MeshError> {
    let scan = scan::Scan::run(name, bytes)?;
    let (piece_at, np, nc) = scan.piece()?;
    assemble::build(&scan.file, &scan.arrays, piece_at, np, nc, scan.version)
}
