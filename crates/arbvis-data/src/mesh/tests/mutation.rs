//! Deterministic mutation test: the fixtures with random edits must never make a reader
//! panic, and must be read (or refused) quickly. `tests/mesh_mutation.rs` runs the same
//! cases under a global allocation cap.

use std::path::Path;
use std::time::Instant;

use super::fixtures::{all_fixtures, mutate, Rng};
use crate::mesh::parse;

#[test]
fn mutated_fixtures_never_panic() {
    let fixtures = all_fixtures();
    // ARBVIS_MUTATION_CASES runs more cases (a longer search, not timed).
    let cases: usize = std::env::var("ARBVIS_MUTATION_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4000);
    let mut rng = Rng::new(0x5eed_2004);
    let start = Instant::now();
    let (mut accepted, mut refused) = (0, 0);
    for case in 0..cases {
        let (name, base) = &fixtures[case % fixtures.len()];
        let bytes = mutate(base, &mut rng);
        let result =
            std::panic::catch_unwind(|| parse(Path::new(name), &bytes).map(|m| m.tets.len()));
        match result {
            Err(_) => panic!(
                "case {case} ({name}) panicked on {:?}",
                String::from_utf8_lossy(&bytes)
            ),
            Ok(Ok(_)) => accepted += 1,
            Ok(Err(e)) => {
                let e = e.to_string();
                assert!(e.starts_with(&format!("{name}: ")), "{e}");
                assert!(!e.contains("cannot allocate"), "case {case}: {e}");
                refused += 1;
            }
        }
    }
    let took = start.elapsed();
    println!("{accepted} accepted, {refused} refused in {took:?}");
    assert!(refused > 2000, "{refused}");
    if cases == 4000 {
        assert!(took.as_secs_f64() < 2.0, "{took:?}");
    }
}
