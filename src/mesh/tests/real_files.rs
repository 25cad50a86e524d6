//! The real files in ../shared/data/tets.

use super::shared;
use crate::mesh::{describe, read};

#[test]
fn print_all() {
    for f in [
        "post.vtk",
        "tetraMesh.vtk",
        "Tetrahedron.vtu",
        "can.vtu",
        "bracket-2.2.msh",
        "bracket-4.1.msh",
        "bracket-4.1-binary.msh",
    ] {
        let Some(p) = shared(&format!("tets/{f}")) else {
            return;
        };
        match read(&p) {
            Ok(m) => println!("{}", describe(&m)),
            Err(e) => println!("ERROR {e}"),
        }
    }
}
