//! Where a sample is, as an MDIO dataset says it: a depth dataset's sample axis in metres
//! (mdio-python's `PostStack3DDepth`), and each trace's map position (`cdp_x`, `cdp_y`)
//! carried from the dataset into a store converted from it and shown under the pointer
//! over a section in the viewer. Skipped like `mdio.rs` without mdio-python.

use std::process::Command;

use crate::mdio::{convert_quietly, f3_ingested};
use arbvis::store::meta::SampleAxis;
use arbvis::store::Store;

#[test]
fn a_depth_dataset_keeps_its_depths_and_map_positions_into_a_store() {
    let Some((dir, sgy, mdio)) = f3_ingested("mdio-depth", "depth", "PostStack3DDepth") else {
        return;
    };
    let dataset = Store::open(&mdio).unwrap();
    // mdio-python numbers the depth axis from the SEG-Y's 4 ms interval as 0, 4, ... m.
    let depth = SampleAxis {
        domain: "depth".into(),
        unit: "m".into(),
        first: 0.0,
        step: 4.0,
    };
    assert_eq!(dataset.meta.source.sample_axis(), depth);
    assert_eq!(dataset.meta.source.interval_us, None);
    crate::common::assert_says(
        &crate::common::inspect(&mdio),
        &["sample: 75, depth 0..296 m (every 4 m)"],
    );
    // The dataset's positions are the SEG-Y's (arbvis's own reader, through a store
    // converted from the SEG-Y): the same numbers to the bit.
    let theirs = dataset.map_coordinates().unwrap().expect("cdp_x, cdp_y");
    let from_segy = dir.join("segy.zarr");
    convert_quietly(&sgy, &from_segy, Some(16));
    let ours = Store::open(&from_segy).unwrap().map_coordinates().unwrap();
    assert_eq!(ours.as_ref(), Some(&theirs));
    assert_eq!(theirs[0].len(), 23 * 18);
    // Converted into a store of its own: depth and positions carried, a depth template.
    let copy = dir.join("copy.zarr");
    convert_quietly(&mdio, &copy, Some(16));
    let store = Store::open(&copy).unwrap();
    assert_eq!(store.meta.source.sample_axis(), depth);
    assert_eq!(store.map_coordinates().unwrap().as_ref(), Some(&theirs));
    let root = std::fs::read_to_string(copy.join("zarr.json")).unwrap();
    assert!(root.contains("\"PostStack3DDepth\""), "{root}");
    let depths = Command::new("python3")
        .args([
            "-c",
            "import sys, zarr; print(zarr.open_group(sys.argv[1])['depth'][:3].tolist())",
        ])
        .arg(&copy)
        .output()
        .unwrap();
    let depths = String::from_utf8_lossy(&depths.stdout);
    assert!(
        depths.contains("[0, 4, 8]") || depths.contains("[0.0, 4.0, 8.0]"),
        "{depths}"
    );
    #[cfg(feature = "viewer")]
    pointer_over_a_section(&store, &theirs);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The viewer's read-out under the pointer over each section: the voxel's inline,
/// crossline and depth, and its trace's map position, in a window that does not start at
/// the survey's corner.
#[cfg(feature = "viewer")]
fn pointer_over_a_section(store: &Store, xy: &[Vec<f64>; 2]) {
    use arbvis::viewer::data::SectionGrid;
    use arbvis::viewer::store_sections::MapPositions;
    use arbvis::volume::axes::store_axes;
    use std::sync::Arc;
    // Samples 10..70, crosslines 3..17, inlines 2..21 of the 75 x 18 x 23 survey.
    let window = [[10, 3, 2], [70, 17, 21]];
    let axes = store_axes(&store.meta, window);
    assert_eq!(
        axes.each_ref().map(|a| a.name.as_str()),
        ["depth (m)", "crossline", "inline"]
    );
    let grid = SectionGrid {
        axes,
        dims: [60, 14, 19],
        half: glam::DVec3::ONE,
        present: vec![0],
        positions: Some(Arc::new(MapPositions {
            xy: xy.clone(),
            crosslines: 18,
            origin: [3, 2],
        })),
    };
    // Inline section 5 (inline 111 + 2 + 5 = 118): the pointer a quarter across (crossline
    // 14 / 4 = voxel 3, crossline 875 + 3 + 3 = 881) and 0.9 down (voxel 54, depth
    // (10 + 54) * 4 = 256 m).
    let text = grid.point(2, 5, 0.25, 0.9);
    let t = (2 + 5) * 18 + 3 + 3;
    let want = format!(
        "inline 118, crossline 881, depth (m) 256\nmap x {:.1}, y {:.1}",
        xy[0][t], xy[1][t]
    );
    assert_eq!(text, want);
    // A time slice: crossline across, inline down; the last voxel at the far edge.
    let text = grid.point(0, 0, 1.0, 1.0);
    let t = (2 + 18) * 18 + 3 + 13;
    assert!(
        text.starts_with("inline 131, crossline 891, depth (m) 40\n"),
        "{text}"
    );
    assert!(text.ends_with(&format!("y {:.1}", xy[1][t])), "{text}");
}
