//! Clouds handed over in memory (`arbvis.Cloud`, from numpy arrays or a `laspy.LasData`),
//! shelved by name ([`crate::memory`]): `cloud = { memory = "cloud-1" }`.

use std::sync::Arc;

use super::{PointCloud, PointsError};
use crate::memory::Shelf;

/// The clouds handed over, by name.
pub static CLOUDS: Shelf<PointCloud> = Shelf::new("cloud");

/// Shelve `cloud`; its name.
pub fn register(cloud: &Arc<PointCloud>) -> String {
    CLOUDS.register(cloud)
}

/// The cloud named `name`, a copy.
pub fn load(name: &str) -> Result<PointCloud, PointsError> {
    CLOUDS
        .copy(name)
        .map_err(|e| PointsError::Invalid(e.to_string()))
}
