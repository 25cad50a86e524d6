//! Surveys handed over in memory (`arbvis.Volume`, from a numpy array or an xarray
//! DataArray), shelved by name ([`crate::memory`]): `volume = { memory = "volume-1" }`.

use std::sync::Arc;

use super::{Limits, Volume, VolumeError};
use crate::memory::Shelf;

/// The volumes handed over, by name.
pub static VOLUMES: Shelf<Volume> = Shelf::new("volume");

/// Shelve `volume`; its name.
pub fn register(volume: &Arc<Volume>) -> String {
    VOLUMES.register(volume)
}

/// The volume named `name`, a copy checked against `limits` as a file's dimensions are.
pub fn load(name: &str, limits: &Limits) -> Result<Volume, VolumeError> {
    let volume = VOLUMES
        .get(name)
        .ok_or_else(|| VolumeError::Invalid(VOLUMES.missing(name).to_string()))?;
    // The dimensions checked before the copy is made.
    limits.check(volume.dims, &format!("memory = {name:?}"))?;
    Ok((*volume).clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_shelved_volume_is_loaded_within_the_limits_while_it_lives() {
        let samples = (0..24).map(|x| x as f32).collect();
        let v = Arc::new(Volume::new([2, 3, 4], [1.0, 2.0, 3.0], samples).unwrap());
        let name = register(&v);
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
