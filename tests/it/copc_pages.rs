//! The COPC hierarchy read a page at a time (issue 28, item 1). laspy's
//! `simple_with_page.copc.laz` keeps the subtree under (2, 0, 0, 0) (5 of its 65 nodes)
//! in a child page: opening reads the root page only, a view that does not reach that key
//! leaves the child page unread, one that does reads it, and every cut equals the one made
//! with the whole hierarchy read first. A damaged child page is an error naming its entry's
//! byte when a view reaches it, not before.

use arbvis::camera::Projection;
use arbvis::points::copc::Copc;
use arbvis::points::copc_lod::{select, View};

use crate::common::splats::camera_turned as camera;
use crate::common::{data_file, temp_dir};

const FILE: &str = "points/simple_with_page.copc.laz";

#[test]
fn opening_reads_the_root_page_and_a_view_reads_what_it_reaches() {
    let lazy = Copc::open(&data_file(FILE)).unwrap();
    assert_eq!(lazy.pages(), (1, 1));
    assert_eq!(lazy.nodes_read().len(), 60);
    assert_eq!(lazy.unread_pages(), [[2, 0, 0, 0]]);
    let front = camera(Projection::Orthographic, 1.0, [0.0, 0.0, 0.0, 1.0]);
    // A thumbnail: only the root is over 150 px; the child page stays unread.
    let small = select(&lazy, &View::of(&front, [64, 48]), 1_000_000, 150.0).unwrap();
    assert_eq!(small.nodes.len(), 1);
    assert_eq!(lazy.pages(), (1, 1));
    // 1600 x 900 takes every node of levels 0-2, (2, 0, 0, 0) among them: its page is read.
    let large = select(&lazy, &View::of(&front, [1600, 900]), 1_000_000, 150.0).unwrap();
    assert_eq!(large.nodes.len(), 1 + 4 + 12);
    assert!(large.nodes.iter().any(|n| n.key == [2, 0, 0, 0]));
    assert_eq!(lazy.pages(), (2, 0));
    assert_eq!(lazy.nodes_read().len(), 65);
}

#[test]
fn every_cut_equals_the_cut_of_the_whole_hierarchy() {
    let eager = Copc::open(&data_file(FILE)).unwrap();
    assert_eq!(eager.all_nodes().unwrap().len(), 65);
    assert_eq!(eager.pages(), (2, 0));
    // Rotated cameras, both projections, zooms from the whole cloud to a corner, odd
    // sizes, budgets from under the root to every point, with and without a pixel size.
    let mut reached = 0;
    let mut left = 0;
    for (k, rotation) in [
        [0.0, 0.0, 0.0, 1.0],
        [0.3, -0.5, 0.1, 0.8],
        [0.2, 0.6, -0.1, 0.75],
        [-0.7, 0.1, 0.4, 0.3],
    ]
    .into_iter()
    .enumerate()
    {
        for projection in [Projection::Orthographic, Projection::Perspective] {
            for zoom in [0.6, 1.7, 4.5] {
                for (budget, pixels) in [(10, 0.0), (100, 150.0), (400, 0.0), (1065, 150.0)] {
                    let size = [317 + 200 * k as u32, 233];
                    let view = View::of(&camera(projection, zoom, rotation), size);
                    let lazy = Copc::open(&data_file(FILE)).unwrap();
                    let cut = select(&lazy, &view, budget, pixels).unwrap();
                    assert_eq!(
                        cut,
                        select(&eager, &view, budget, pixels).unwrap(),
                        "{rotation:?} {projection:?} zoom {zoom} budget {budget}"
                    );
                    // The child page is read when the cut reaches its key (also when the
                    // view would have taken the key had its points fitted the budget).
                    let has = cut
                        .nodes
                        .iter()
                        .any(|n| n.key[0] >= 2 && n.key[1..] == [0, 0, 0]);
                    if has {
                        assert_eq!(lazy.pages(), (2, 0));
                    }
                    reached += usize::from(has);
                    left += usize::from(lazy.pages() == (1, 1));
                }
            }
        }
    }
    // Both cases were met: the page read, and left unread.
    assert!(reached > 0 && left > 0, "{reached} {left}");
}

#[test]
fn a_damaged_child_page_is_an_error_when_a_view_reaches_it() {
    let bytes = std::fs::read(data_file(FILE)).unwrap();
    // The child page: the root page's entry for (2, 0, 0, 0) names it.
    let vlr = 375 + 54;
    let root = u64::from_le_bytes(bytes[vlr + 40..vlr + 48].try_into().unwrap()) as usize;
    let size = u64::from_le_bytes(bytes[vlr + 48..vlr + 56].try_into().unwrap()) as usize;
    let entry = (root..root + size)
        .step_by(32)
        .find(|&e| bytes[e + 28..e + 32] == (-1i32).to_le_bytes())
        .expect("a child page");
    let page = u64::from_le_bytes(bytes[entry + 16..entry + 24].try_into().unwrap()) as usize;
    // Its second entry at level 99.
    let mut b = bytes.clone();
    b[page + 32..page + 36].copy_from_slice(&99i32.to_le_bytes());
    let path = temp_dir("copc-pages").join("page.copc.laz");
    std::fs::write(&path, &b).unwrap();
    let c = Copc::open(&path).expect("the root page is sound");
    let front = camera(Projection::Orthographic, 1.0, [0.0, 0.0, 0.0, 1.0]);
    select(&c, &View::of(&front, [64, 48]), 1_000_000, 150.0).expect("the root only");
    let e = select(&c, &View::of(&front, [1600, 900]), 1_000_000, 150.0)
        .expect_err("the page is reached")
        .to_string();
    assert!(
        e.contains("page.copc.laz")
            && e.contains(&format!("at byte {}", page + 32))
            && e.contains("level 99"),
        "{e}"
    );
    // The error stands: asked again, the held file never answers with a partial
    // hierarchy, and nothing of the failed page was added.
    let again = c.all_nodes().expect_err("still refused").to_string();
    assert_eq!(again, e);
    assert!(select(&c, &View::of(&front, [1600, 900]), 1_000_000, 150.0).is_err());
    assert_eq!(c.nodes_read().len(), 60);
    // `inspect` reads every page: the same error.
    let e = arbvis::points::inspect(&path)
        .expect_err("refused")
        .to_string();
    assert!(e.contains("level 99"), "{e}");
    // A child page entry outside its key's subtree (under (2, 0, 0, 0) only: (5, 31, 31,
    // 31) lies under (2, 3, 3, 3)): refused, naming the entry.
    let mut b = bytes.clone();
    for (o, v) in [(0, 5i32), (4, 31), (8, 31), (12, 31)] {
        b[page + 32 + o..page + 36 + o].copy_from_slice(&v.to_le_bytes());
    }
    let other = temp_dir("copc-pages-subtree").join("subtree.copc.laz");
    std::fs::write(&other, &b).unwrap();
    let c = Copc::open(&other).expect("the root page is sound");
    let e = c.all_nodes().expect_err("refused").to_string();
    assert!(
        e.contains(&format!("at byte {}", page + 32))
            && e.contains("a child page holds [2, 0, 0, 0]"),
        "{e}"
    );
    // A page named inside the root page (its second entry): its entry read again is
    // refused as an overlap, naming that byte.
    let mut b = bytes.clone();
    b[entry + 16..entry + 24].copy_from_slice(&(root as u64 + 32).to_le_bytes());
    b[entry + 24..entry + 28].copy_from_slice(&32i32.to_le_bytes());
    std::fs::write(&path, &b).unwrap();
    let c = Copc::open(&path).expect("the root page is sound");
    let e = c.all_nodes().expect_err("refused").to_string();
    assert!(
        e.contains(&format!("at byte {}", root + 32)) && e.contains("overlaps"),
        "{e}"
    );
    // A page named past the hierarchy EVLR: refused where it is named (the root page, read
    // at opening), naming the entry.
    let mut b = bytes.clone();
    b[entry + 16..entry + 24].copy_from_slice(&(bytes.len() as u64).to_le_bytes());
    std::fs::write(&path, &b).unwrap();
    let e = Copc::open(&path).err().expect("refused").to_string();
    assert!(
        e.contains(&format!("at byte {entry}")) && e.contains("inside a hierarchy EVLR"),
        "{e}"
    );
}

/// laspy reads every point of a COPC file (`CopcReader.query()`, following its pages):
/// "X Y Z" lines of the raw integers, sorted.
const LASPY_XYZ: &str = r#"
import sys, laspy
with laspy.CopcReader.open(sys.argv[1]) as r:
    p = r.query()
rows = sorted("%d %d %d" % (x, y, z) for x, y, z in zip(p.X, p.Y, p.Z))
print("\n".join(rows))
"#;

/// A cloud deep enough for child pages (a broad spread and a tight cluster that goes
/// down level after level), converted: the root page holds levels 0-2 and the level-3
/// nodes (as entries or as pointers), naming
/// the pages below; arbvis and laspy read every point through them.
#[test]
fn the_writer_pages_a_deep_hierarchy_and_laspy_reads_it() {
    let dir = temp_dir("copc-pages-write");
    let ply = dir.join("deep.ply");
    let mut seed = 0x2545_f491_u64;
    let mut next = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut text = String::from(
        "ply\nformat ascii 1.0\nelement vertex 5000\nproperty double x\nproperty double y\nproperty double z\nend_header\n",
    );
    for k in 0..5000 {
        let (spread, centre) = if k < 2000 { (100.0, 0.0) } else { (0.05, 37.3) };
        let p = [next(), next(), next()].map(|v| centre + spread * v);
        text.push_str(&format!("{:.4} {:.4} {:.4}\n", p[0], p[1], p[2]));
    }
    std::fs::write(&ply, text).unwrap();
    let out = dir.join("deep.copc.laz");
    crate::common::stdout_of(
        std::process::Command::new(env!("CARGO_BIN_EXE_arbvis"))
            .arg("convert")
            .arg(&ply)
            .arg(&out)
            .args(["--node-points", "50"]),
    );
    let c = Copc::open(&out).unwrap();
    let (read, unread) = c.pages();
    assert_eq!(read, 1);
    assert!(unread > 0, "a deep cloud's hierarchy is paged");
    assert!(
        c.nodes_read().iter().all(|n| n.key[0] < 5),
        "the root page: levels 0-4"
    );
    let nodes = c.all_nodes().unwrap();
    assert!(
        nodes.iter().any(|n| n.key[0] >= 5),
        "deeper levels in child pages"
    );
    assert_eq!(nodes.iter().map(|n| n.points).sum::<u64>(), 5000);
    // arbvis's reader: every point through the pages, as raw integers.
    let mut ours = Vec::new();
    for n in &nodes {
        let pd = c.read_node(n).unwrap();
        let cols = crate::common::las_columns(&pd);
        ours.extend(crate::common::rows_of(&cols[..3], pd.len()));
    }
    ours.sort();
    assert_eq!(ours.len(), 5000);
    // And as a scene's cloud, every budget's whole-level cut read through the pages.
    let cloud = arbvis::points::PointSource::copc(out.clone(), 1 << 40)
        .load(std::path::Path::new("."))
        .unwrap();
    assert_eq!(cloud.len(), 5000);
    if !crate::common::python_has(
        "import laspy, lazrs",
        "python3 with laspy and lazrs is missing (pip install laspy lazrs)",
    ) {
        return;
    }
    let theirs: Vec<String> = crate::common::stdout_of(
        std::process::Command::new("python3")
            .args(["-c", LASPY_XYZ])
            .arg(&out),
    )
    .lines()
    .map(str::to_string)
    .collect();
    assert!(ours == theirs, "laspy reads other points");
}
