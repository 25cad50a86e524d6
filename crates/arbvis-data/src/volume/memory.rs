//! Volumes handed over in memory (an `arbvis.Volume` made in Python from a numpy array or
//! an xarray DataArray): each is registered under a name, and a scene names it as it names
//! a file, `volume = { memory = "volume-1" }`. The registry holds them weakly: a volume
//! lives as long as its owners (the Python object, the scenes it was put in), and a
//! scene naming one that is gone, or one made in another process, says so.

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock, Weak};

use super::{Limits, Volume, VolumeError};

/// The last number given, and the volumes by name.
type Registry = Mutex<(u64, HashMap<String, Weak<Volume>>)>;

fn registry() -> &'static Registry {
    static REGISTRY: OnceLock<Registry> = OnceLock::new();
    REGISTRY.get_or_init(Default::default)
}

/// Register `volume`; its name (`volume-N`, never reused in this process).
pub fn register(volume: &Arc<Volume>) -> String {
    let mut guard = registry().lock().unwrap_or_else(|e| e.into_inner());
    let (next, map) = &mut *guard;
    *next += 1;
    let name = format!("volume-{next}");
    // Names of volumes that are gone are dropped as new ones come.
    map.retain(|_, v| v.strong_count() > 0);
    map.insert(name.clone(), Arc::downgrade(volume));
    name
}

/// The volume registered as `name`, while one of its owners holds it.
pub fn get(name: &str) -> Option<Arc<Volume>> {
    let guard = registry().lock().unwrap_or_else(|e| e.into_inner());
    guard.1.get(name).and_then(Weak::upgrade)
}

/// The volume named `name`, a copy checked against `limits` as a file's dimensions are.
pub fn load(name: &str, limits: &Limits) -> Result<Volume, VolumeError> {
    let volume = get(name).ok_or_else(|| {
        VolumeError::Invalid(format!(
            "memory = {name:?}: no such volume in this process (an arbvis.Volume lives in the process that made it, while it or a scene holding it is referenced)"
        ))
    })?;
    limits.check(volume.dims, &format!("memory = {name:?}"))?;
    Ok((*volume).clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_registered_volume_is_found_while_it_lives() {
        let v = Arc::new(
            Volume::new(
                [2, 3, 4],
                [1.0, 2.0, 3.0],
                (0..24).map(|x| x as f32).collect(),
            )
            .unwrap(),
        );
        let name = register(&v);
        let again = register(&v);
        assert_ne!(name, again, "every registration has its own name");
        let got = load(&name, &Limits::default()).unwrap();
        assert_eq!(
            (got.dims, got.spacing, got.values.len()),
            (v.dims, v.spacing, 24)
        );
        let small = Limits {
            max_side: 3,
            ..Limits::default()
        };
        assert!(load(&name, &small)
            .unwrap_err()
            .to_string()
            .contains("exceed"));
        drop(v);
        let e = load(&name, &Limits::default()).unwrap_err().to_string();
        assert!(e.contains("no such volume in this process"), "{e}");
    }
}
