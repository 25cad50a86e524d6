//! Every program in `programs/` compiles on the running driver (all failures reported at
//! once), nothing in `programs/` goes unembedded, and broken programs report the program
//! name, line, column and the driver's message.

use crate::common;

use std::path::Path;

use arbvis::gl::{Backend, GlError, Program, ProgramKind, ProgramText};
use arbvis::programs;
use common::headless;

#[test]
fn every_program_compiles_on_this_driver() {
    let h = headless(Backend::Egl);
    let gpu = h.gpu();
    let mut failures = Vec::new();
    let pairs = arbvis::catalog::all_program_pairs();
    for pair in &pairs {
        if let Err(e) = Program::new(gpu, pair.kind, &pair.vertex, &pair.fragment) {
            failures.push(format!(
                "{} + {}: {e}",
                pair.vertex.name, pair.fragment.name
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} program pairs failed:\n{}",
        failures.len(),
        pairs.len(),
        failures.join("\n")
    );
}

#[test]
fn every_file_in_programs_is_embedded() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("programs");
    let embedded: Vec<String> = programs::all_texts()
        .iter()
        .map(|t| t.name.to_string())
        .collect();
    let mut missing = Vec::new();
    for dir in std::fs::read_dir(&root).unwrap() {
        let dir = dir.unwrap().path();
        if !dir.is_dir() {
            continue;
        }
        for file in std::fs::read_dir(&dir).unwrap() {
            let file = file.unwrap().path();
            let name = format!(
                "{}/{}",
                dir.file_name().unwrap().to_string_lossy(),
                file.file_name().unwrap().to_string_lossy()
            );
            if !embedded.contains(&name) {
                missing.push(name);
            }
        }
    }
    assert!(
        missing.is_empty(),
        "in programs/ but not in src/programs.rs: {missing:?}"
    );
    // And every embedded text equals its file, byte for byte.
    for t in programs::all_texts() {
        let on_disk = std::fs::read(root.join(&*t.name)).unwrap();
        assert_eq!(
            on_disk,
            t.text.as_bytes(),
            "{} differs from its file",
            t.name
        );
    }
}

fn fixture(name: &str) -> ProgramText {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/broken")
        .join(name);
    ProgramText {
        name: format!("broken/{name}").into(),
        text: std::fs::read_to_string(path).unwrap().into(),
    }
}

/// Compile `broken` with a working partner of the same kind and return the error.
fn compile_error(
    kind: ProgramKind,
    broken: &ProgramText,
    broken_is_vertex: bool,
) -> arbvis::gl::CompileError {
    let h = headless(Backend::Egl);
    let good_vertex = match kind {
        ProgramKind::Arb => programs::TRANSFORM_ARBVP,
        ProgramKind::Glsl => programs::TRANSFORM_VERT,
    };
    let good_fragment = match kind {
        ProgramKind::Arb => programs::QUAD_ARBFP,
        ProgramKind::Glsl => programs::QUAD_FRAG,
    };
    let result = if broken_is_vertex {
        Program::new(h.gpu(), kind, broken, &good_fragment)
    } else {
        Program::new(h.gpu(), kind, &good_vertex, broken)
    };
    match result {
        Err(GlError::Compile(e)) => e,
        Err(other) => panic!("expected a compile error, got {other}"),
        Ok(_) => panic!("{} compiled", broken.name),
    }
}

#[test]
fn arb_typo_reports_line_and_column() {
    let e = compile_error(ProgramKind::Arb, &fixture("typo.arbfp"), false);
    assert_eq!(e.program, "broken/typo.arbfp");
    assert_eq!((e.line, e.column), (4, Some(1)), "{e}");
    assert_eq!(e.source_line, "MOVE c, fragment.texcoord[0];");
    assert!(!e.message.is_empty());
    let shown = e.to_string();
    assert!(shown.starts_with("broken/typo.arbfp:4:1: "), "{shown}");
    assert!(
        shown.contains(&e.message) && shown.contains("MOVE c"),
        "{shown}"
    );
}

#[test]
fn arb_error_in_joined_string_has_column_on_line_one() {
    let text = fixture("joined.arbfp");
    let e = compile_error(ProgramKind::Arb, &text, false);
    assert_eq!(e.line, 1, "{e}");
    let col = e.column.expect("a column") as usize;
    // The driver points at or just after the undeclared name.
    let at = text.text.find("undeclared").unwrap() + 1;
    assert!(
        (at..=at + "undeclared".len()).contains(&col),
        "column {col}, name at {at}: {e}"
    );
}

#[test]
fn arb_vertex_program_error_is_positioned() {
    let e = compile_error(ProgramKind::Arb, &fixture("bad_attr.arbvp"), true);
    assert_eq!(e.program, "broken/bad_attr.arbvp");
    assert_eq!(e.line, 3, "{e}");
    assert!(e.column.is_some(), "{e}");
}

#[test]
fn glsl_error_reports_line_and_column() {
    let e = compile_error(ProgramKind::Glsl, &fixture("undeclared.frag"), false);
    assert_eq!(e.program, "broken/undeclared.frag");
    assert_eq!(e.line, 5, "{e}");
    assert!(e.column.is_some(), "{e}");
    assert!(e.message.contains("undeclared_gain"), "{e}");
    assert_eq!(
        e.source_line.trim(),
        "frag_color = v_texcoord0 * undeclared_gain;"
    );
}

#[test]
fn no_gl_error_left_behind_after_a_failed_compile() {
    let h = headless(Backend::Egl);
    let _ = Program::new(
        h.gpu(),
        ProgramKind::Arb,
        &programs::TRANSFORM_ARBVP,
        &fixture("typo.arbfp"),
    );
    arbvis::gl_check!(h.gpu()).expect("the failed compile consumed its own error");
}
