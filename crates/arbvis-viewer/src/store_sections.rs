//! Sections of a survey streamed from a store: the inline, crossline and time sections
//! are read from the store at level 0 (full resolution), whatever the brick cache holds
//! on the GPU, by a reader thread so that the frame never waits for the disk; until a
//! section arrives the panel shows the previous one.
//!
//! Decisions: a section is one voxel thick, read with [`Store::window`] (every chunk the
//! plane crosses, decompressed whole: a time slice of a 2,200 x 2,200 survey in bricks of
//! 64 is 1,225 chunks), quantized over the scene's range for the attribute as the brick
//! cache quantizes it, so the section and the 3D view show the same levels. The axes come
//! from the store's geometry (SEG-Y time, crossline and inline numbers).

use std::path::Path;
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::Arc;

use glam::DVec3;

use arbvis_data::store::{Store, StoreError};
use arbvis_data::volume::axes::{store_axes, Axis};
use arbvis_data::volume::quantize::quantize_value;
use arbvis_techniques::error::{RenderError, RenderResult};
use arbvis_techniques::techniques::opacity3d::bricked::StoreScene;
use arbvis_techniques::techniques::opacity3d::Opacity3dScene;

/// Map positions (`cdp_x`, `cdp_y`) of a survey's traces, and where the shown window
/// starts in it.
pub struct MapPositions {
    /// x, then y, per trace, inline-major over the whole survey.
    pub xy: [Vec<f64>; 2],
    /// Crosslines in the whole survey.
    pub crosslines: usize,
    /// The window's first crossline and inline (voxel indices in the survey).
    pub origin: [usize; 2],
}

impl MapPositions {
    /// The position of the trace at crossline `j`, inline `k` of the window, if known.
    pub fn at(&self, j: usize, k: usize) -> Option<[f64; 2]> {
        let t = (self.origin[1] + k) * self.crosslines + self.origin[0] + j;
        let p = [*self.xy[0].get(t)?, *self.xy[1].get(t)?];
        p.iter().all(|v| v.is_finite()).then_some(p)
    }
}

/// A request: (axis, index, attribute).
pub type SectionKey = (usize, usize, usize);

/// The store behind the sections, its geometry and the reader thread.
pub struct StoreSections {
    /// Level-0 voxels of the window shown.
    pub dims: [usize; 3],
    /// The box's half extents (as the 3D view's).
    pub half: DVec3,
    /// The axes, in the survey's numbers.
    pub axes: [Axis; 3],
    /// Per scene attribute: the store's attribute index and the quantization range.
    pub attributes: [Option<(usize, f64, f64)>; 3],
    /// Each trace's map position, where the store has one.
    pub positions: Option<Arc<MapPositions>>,
    window: [[usize; 3]; 2],
    requests: Sender<Request>,
    replies: Receiver<Reply>,
    asked: Option<SectionKey>,
}

impl StoreSections {
    /// The sections of the store `params` names (relative to `base`), if it names one.
    pub fn open(params: &Opacity3dScene, base: &Path) -> RenderResult<Option<StoreSections>> {
        let Some(StoreScene {
            store,
            pyramid,
            attributes,
            ..
        }) = StoreScene::open(params, base)?
        else {
            return Ok(None);
        };
        let meta = &store.meta;
        let window = pyramid.window;
        let dims: [usize; 3] = std::array::from_fn(|a| window[1][a].saturating_sub(window[0][a]));
        let axes = store_axes(meta, window);
        // Map positions for the pointer's read-out: a missing or unreadable pair costs the
        // read-out only, never the view.
        let positions = match store.map_coordinates() {
            Ok(xy) => xy.map(|xy| {
                Arc::new(MapPositions {
                    xy,
                    crosslines: meta.dims[1],
                    origin: [window[0][1], window[0][2]],
                })
            }),
            Err(e) => {
                eprintln!("map coordinates not shown: {e}");
                None
            }
        };
        let (req_tx, req_rx) = channel();
        let (rep_tx, rep_rx) = channel();
        let reader = store.clone();
        std::thread::Builder::new()
            .name("arbvis section reader".into())
            .spawn(move || read_sections(&reader, req_rx, rep_tx))
            .map_err(RenderError::Thread)?;
        Ok(Some(StoreSections {
            dims,
            half: pyramid.half(),
            axes,
            attributes,
            positions,
            window,
            requests: req_tx,
            replies: rep_rx,
            asked: None,
        }))
    }

    /// Ask for section `key` (axis, index within the window, scene attribute) unless it
    /// is the one already asked for.
    pub fn ask(&mut self, key: SectionKey) {
        if self.asked == Some(key) {
            return;
        }
        let Some((attr, low, high)) = self.attributes[key.2] else {
            return;
        };
        self.asked = Some(key);
        let _ = self
            .requests
            .send((key, plane(self.window, key.0, key.1), attr, low, high));
    }

    /// The sections read since the last call: key and its quantized levels (across
    /// fastest, as [`arbvis_data::volume::axes::section_axes`] orders them), or the error.
    pub fn arrived(&mut self) -> Vec<Reply> {
        self.replies.try_iter().collect()
    }
}

/// Voxels `lo .. hi` of the section at `index` along `axis` of `window`.
pub fn plane(window: [[usize; 3]; 2], axis: usize, index: usize) -> [[usize; 3]; 2] {
    let mut lo = window[0];
    let mut hi = window[1];
    let at = (window[0][axis] + index).min(window[1][axis].saturating_sub(1));
    lo[axis] = at;
    hi[axis] = at + 1;
    [lo, hi]
}

/// Level-0 values of `attr` over `region` (one voxel thick) quantized over `low..high`,
/// ordered as the section shows them: across fastest, then down.
pub fn section_levels(
    store: &Store,
    attr: usize,
    axis: usize,
    region: [[usize; 3]; 2],
    low: f64,
    high: f64,
) -> Result<Vec<u8>, StoreError> {
    let v = store.window(attr, region[0], region[1])?;
    // The window is one voxel thick along `axis`: its voxel 0 there.
    let (_, voxels) = arbvis_data::volume::axes::section_voxels(v.dims, axis, 0);
    let out = voxels
        .map(|[i, j, k]| quantize_value(v.values[v.index(i, j, k)], low, high))
        .collect();
    Ok(out)
}

/// A section to read: key, voxel region, store attribute, quantization range.
type Request = (SectionKey, [[usize; 3]; 2], usize, f64, f64);
/// A section read: key and levels, or the error.
type Reply = (SectionKey, Result<Vec<u8>, StoreError>);

fn read_sections(store: &Store, requests: Receiver<Request>, replies: Sender<Reply>) {
    while let Ok(mut next) = requests.recv() {
        // Only the newest request matters (the slider moved on).
        while let Ok(newer) = requests.try_recv() {
            next = newer;
        }
        let (key, region, attr, low, high) = next;
        let levels = section_levels(store, attr, key.0, region, low, high);
        if replies.send((key, levels)).is_err() {
            return;
        }
    }
}
