//! Hostile clouds and surfaces made here (issue 17): each is a legal or nearly legal file
//! that once made a loader allocate, run or report what it should not. Shared by
//! `tests/fuzz.rs` (fixed cases) and `tests/hostile.rs` (through the binary).
#![allow(dead_code)]

use std::io::Cursor;

use las::point::Format;
use las::{Builder, Color, Point, Transform, Vector, Vlr, Writer};

/// One Extra Bytes descriptor of a u8 attribute called `label` (LAS 1.4 R15, 192 bytes).
fn u8_descriptor(label: &str) -> Vec<u8> {
    let mut d = vec![0u8; 192];
    d[2] = 1; // unsigned char
    d[4..4 + label.len()].copy_from_slice(label.as_bytes());
    d
}

/// A LAS 1.4 file (format 6; LAZ when `compressed`) of `n` points on a 7 x 11 lattice,
/// each with `extras` one-byte extra-bytes attributes (all 7) described in one Extra
/// Bytes VLR.
pub fn las14(n: usize, extras: usize, compressed: bool) -> Vec<u8> {
    let mut b = Builder::default();
    b.version = (1, 4).into();
    b.point_format = Format::new(6).unwrap();
    b.point_format.is_compressed = compressed;
    b.point_format.extra_bytes = extras as u16;
    let t = |offset: f64| Transform {
        scale: 0.01,
        offset,
    };
    b.transforms = Vector {
        x: t(600_000.0),
        y: t(4_100_000.0),
        z: t(0.0),
    };
    if extras > 0 {
        b.vlrs.push(Vlr {
            user_id: "LASF_Spec".into(),
            record_id: 4,
            description: "extra bytes".into(),
            data: (0..extras)
                .flat_map(|k| u8_descriptor(&format!("e{k}")))
                .collect(),
        });
    }
    let mut w = Writer::new(Cursor::new(Vec::new()), b.into_header().unwrap()).unwrap();
    for i in 0..n {
        w.write_point(Point {
            x: 600_000.0 + (i % 7) as f64,
            y: 4_100_000.0 + (i % 11) as f64,
            z: 12.5,
            gps_time: Some(0.0),
            extra_bytes: vec![7; extras],
            ..Default::default()
        })
        .unwrap();
    }
    w.close().unwrap();
    w.into_inner().unwrap().into_inner()
}

/// A LAZ file (format 3) of `n` equal points: about 85 points a compressed byte.
pub fn equal_points_laz(n: usize) -> Vec<u8> {
    let mut b = Builder::from((1, 2));
    b.point_format = Format::new(3).unwrap();
    b.point_format.is_compressed = true;
    let mut w = Writer::new(Cursor::new(Vec::new()), b.into_header().unwrap()).unwrap();
    let p = Point {
        x: 1.0,
        y: 2.0,
        z: 3.0,
        color: Some(Color::new(1, 2, 3)),
        gps_time: Some(0.0),
        ..Default::default()
    };
    for _ in 0..n {
        w.write_point(p.clone()).unwrap();
    }
    w.close().unwrap();
    w.into_inner().unwrap().into_inner()
}

/// Overwrite `bytes[at..]` with `value`.
pub fn set(bytes: &mut [u8], at: usize, value: &[u8]) {
    bytes[at..at + value.len()].copy_from_slice(value);
}

/// Binary STL of `triangles`.
pub fn binary_stl(triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    arbvis::surface::stl::to_binary(&[b' '; 80], triangles)
}

/// `copies` copies of one face, each lifted by 1e-6 (so no two share a vertex and every
/// pair is tested): a binary STL of 50 bytes a copy.
pub fn face_copies(copies: usize) -> Vec<[[f32; 3]; 3]> {
    (0..copies)
        .map(|c| {
            let z = c as f32 * 1e-6;
            [[0.0, 0.0, z], [1.0, 0.25, z], [0.1, 1.0, z + 0.3]]
        })
        .collect()
}

/// Slivers from one corner of the box to the other (each covering every cell of a fine
/// grid) over a lattice of small triangles: `slivers + lattice²` triangles.
pub fn slivers_over_a_lattice(slivers: usize, lattice: usize) -> Vec<[[f32; 3]; 3]> {
    let mut out = Vec::new();
    let step = 1.0 / lattice as f32;
    for i in 0..lattice {
        for j in 0..lattice {
            let (x, y) = (i as f32 * step, j as f32 * step);
            out.push([
                [x, y, 0.0],
                [x + 0.4 * step, y, 0.0],
                [x, y + 0.4 * step, 0.001],
            ]);
        }
    }
    for k in 0..slivers {
        let z = 0.5 + k as f32 * 1e-3;
        out.push([[0.0, 0.0, z], [1.0, 1.0, z + 0.5], [1.0, 0.999, z + 0.5]]);
    }
    out
}

/// ASCII STL of `facets` triangles all on one line.
pub fn one_line_ascii_stl(facets: usize) -> String {
    let facet =
        "facet normal 0 0 1 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 1 0 endloop endfacet ";
    format!("solid long\n{}endsolid long\n", facet.repeat(facets))
}

/// OBJ text of an open bowl: a sphere of radius 0.6 cut below the equator's 30°
/// south (`nu` x `nv` quads of the full sphere, those above the cut kept).
pub fn open_bowl_obj(nu: usize, nv: usize) -> String {
    let mut text = String::from("# an open bowl\n");
    let keep = nv * 2 / 3;
    for v in 0..=keep {
        for u in 0..nu {
            let (phi, theta) = (
                std::f64::consts::TAU * u as f64 / nu as f64,
                std::f64::consts::PI * v as f64 / nv as f64,
            );
            text += &format!(
                "v {} {} {}\n",
                0.6 * theta.sin() * phi.cos() + 0.03,
                0.6 * theta.sin() * phi.sin() - 0.02,
                0.6 * theta.cos()
            );
        }
    }
    let at = |u: usize, v: usize| v * nu + u % nu + 1;
    for v in 0..keep {
        for u in 0..nu {
            text += &format!(
                "f {} {} {} {}\n",
                at(u, v),
                at(u, v + 1),
                at(u + 1, v + 1),
                at(u + 1, v)
            );
        }
    }
    text
}
