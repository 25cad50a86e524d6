//! The mesh readers under a global allocation cap: mutated fixtures (the same seeded
//! cases as the unit test) and files declaring huge counts must be refused by the count
//! checks, never by running out of memory. An unchecked allocation past the cap aborts
//! this test binary; a checked one (`try_reserve`) would surface as "cannot allocate",
//! which is asserted absent.

#[path = "../src/mesh/tests/fixtures.rs"]
mod fixtures;

use std::path::Path;

use arbvis::mesh::parse;

#[global_allocator]
static ALLOCATOR: cap::Cap<std::alloc::System> = cap::Cap::new(std::alloc::System, usize::MAX);

/// The most one parse of a fixture-sized file may hold at once: the largest honest need
/// is a few hundred kB (a zlib block may declare up to 1032 bytes per compressed byte).
const BUDGET: usize = 64 << 20;

fn check(name: &str, bytes: &[u8]) {
    if let Err(e) = parse(Path::new(name), bytes) {
        let e = e.to_string();
        assert!(!e.contains("cannot allocate"), "{e}");
    }
}

#[test]
fn readers_stay_within_an_allocation_cap() {
    let fixtures = fixtures::all_fixtures();
    // A failing assertion lifts the cap first, so that the panic report (backtrace
    // symbolization allocates a lot) can be printed.
    let report = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let _ = ALLOCATOR.set_limit(usize::MAX);
        report(info)
    }));
    ALLOCATOR.set_limit(ALLOCATOR.allocated() + BUDGET).unwrap();
    // The cap works: more than the budget cannot be had.
    assert!(Vec::<u8>::new().try_reserve_exact(2 * BUDGET).is_err());
    let mut rng = fixtures::Rng::new(0x5eed_2004);
    for case in 0..4000 {
        let (name, base) = &fixtures[case % fixtures.len()];
        let bytes = fixtures::mutate(base, &mut rng);
        check(name, &bytes);
    }
    for (name, base) in &fixtures {
        for from in ["6", "5", "16", "18", "22", "96", "144"] {
            for to in ["1099511627776", "4294967295", "18446744073709551615"] {
                let hits = base
                    .windows(from.len())
                    .enumerate()
                    .filter(|(_, w)| *w == from.as_bytes());
                for (i, _) in hits.take(40) {
                    let mut b = base.clone();
                    b.splice(i..i + from.len(), to.bytes());
                    check(name, &b);
                }
            }
        }
    }
    ALLOCATOR.set_limit(usize::MAX).unwrap();
}
