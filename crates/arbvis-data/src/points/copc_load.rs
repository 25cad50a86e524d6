//! A COPC cloud loaded for a view: the cut chosen ([`copc_lod::select`], or whole levels
//! without a view), its nodes decoded in parallel (those decoded for an earlier cut from
//! the decoded-node cache), the cloud framed by the file, and what the cut holds.
//!
//! The viewer takes it in stages, as Potree loads a few nodes a frame: the missing nodes
//! are decoded a batch at a time in the cut's order (largest on screen first, a parent
//! before its children), and whenever `Stages::every` has passed the nodes ready so far
//! are handed over as a cloud of their own — those whose ancestors in the cut are ready
//! too, so coarser points stand in for the children still loading — when they hold at
//! least twice the points of the last stage (each stage's cloud is built afresh: the
//! stages together cost at most about one more build of the whole cut), then the whole
//! cut.
//! Each stage is a smaller cut of the same view: never over the budget, and its upload
//! takes only the nodes the GPU's node cache lacks.

use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::cloud::PointCloud;
use super::copc::{Copc, CopcSpec, Node};
use super::copc_cache::{self, FileId};
use super::copc_lod::{self, Cut, Loaded, View};
use super::{lasfile, PointsError};

/// When a cut being loaded is handed over before it is whole, and when to give up.
#[derive(Debug, Clone)]
pub struct Stages {
    /// Missing nodes decoded together (in parallel) between two looks at the clock.
    pub batch: usize,
    /// The least time between two stages (the first counts from the start).
    pub every: Duration,
    /// Set by whoever no longer wants the cut (the camera moved on): the loading stops
    /// before its next batch.
    pub stop: Option<Arc<AtomicBool>>,
}

impl Stages {
    /// One stage: the whole cut (`render`, and whoever waits for it).
    pub const WHOLE: Stages = Stages {
        batch: usize::MAX,
        every: Duration::MAX,
        stop: None,
    };

    /// The viewer's: what is ready every 100 ms, nodes decoded two per core at a time.
    pub fn viewer() -> Stages {
        Stages {
            batch: 2 * rayon::current_num_threads(),
            every: Duration::from_millis(100),
            stop: None,
        }
    }

    fn stopped(&self) -> bool {
        self.stop
            .as_ref()
            .is_some_and(|s| s.load(Ordering::Relaxed))
    }
}

/// `spec`'s cloud (relative to `base`) for `view`, whole.
pub fn load(
    spec: &CopcSpec,
    base: &Path,
    view: Option<&View>,
) -> Result<(PointCloud, Loaded), PointsError> {
    let mut out = None;
    load_in_stages(spec, base, view, Stages::WHOLE, |cloud, loaded, _| {
        out = Some((cloud, loaded));
        true
    })?;
    Ok(out.expect("the whole cut is always handed over"))
}

/// `spec`'s cloud for `view` handed to `each` in stages (`stages`): each a cloud, what it
/// holds, and whether it is the whole cut (always the last). `each` returns false to stop
/// (nobody waits for the rest), as does `stages.stop` when set (then nothing more is
/// handed over, the whole cut included).
pub fn load_in_stages(
    spec: &CopcSpec,
    base: &Path,
    view: Option<&View>,
    stages: Stages,
    mut each: impl FnMut(PointCloud, Loaded, bool) -> bool,
) -> Result<(), PointsError> {
    let start = Instant::now();
    let c = copc_cache::open(&crate::fetch::resolve(base, &spec.path))?;
    let cut = match view {
        Some(v) => copc_lod::select(&c, v, spec.points, spec.min_node_pixels)?,
        None => {
            let (nodes, _) = c.cut(spec.points)?;
            let points = nodes.iter().map(|n| n.points).sum();
            Cut::whole(nodes, points, spec.points)
        }
    };
    let file = FileId::of(c.path());
    let missing: Vec<Node> = cut
        .nodes
        .iter()
        .filter(|n| !copc_cache::holds(&file, n.key))
        .copied()
        .collect();
    // A lone root thinned to a stride is one node: no stages.
    if cut.root_stride == 1 && missing.len() > stages.batch {
        let mut last = start;
        let mut handed = 0;
        for batch in missing.chunks(stages.batch.max(1)) {
            if stages.stopped() {
                return Ok(());
            }
            lasfile::decode_nodes(&c, batch)?;
            if last.elapsed() < stages.every {
                continue;
            }
            // A stage at least doubles the points of the last: building the stages costs
            // at most about one more build of the whole cut.
            let part = ready_part(&cut, |n| copc_cache::holds(&file, n.key));
            if part.points >= 2 * handed && part.nodes.len() < cut.nodes.len() {
                handed = part.points.max(1);
                let (cloud, mut loaded) = cloud_of(&c, &part, None)?;
                loaded.describe = format!(
                    "{}; loading: {} of the view's {} nodes",
                    loaded.describe,
                    part.nodes.len(),
                    cut.nodes.len()
                );
                if !each(cloud, loaded, false) {
                    return Ok(());
                }
                last = Instant::now();
            }
        }
    }
    if stages.stopped() {
        return Ok(());
    }
    // Nodes decoded by the stages count as read, not as held from an earlier cut.
    let held = cut.nodes.len() - missing.len();
    let (cloud, loaded) = cloud_of(&c, &cut, Some(held))?;
    each(cloud, loaded, true);
    Ok(())
}

/// The nodes of `cut` that are ready and whose ancestors in the cut are ready, in the
/// cut's order: a smaller cut of the same view.
pub fn ready_part(cut: &Cut, ready: impl Fn(&Node) -> bool) -> Cut {
    let index: std::collections::HashMap<[i32; 4], usize> = cut
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| (n.key, i))
        .collect();
    let mut taken = vec![false; cut.nodes.len()];
    for (i, n) in cut.nodes.iter().enumerate() {
        // The nearest ancestor in the cut (a parent always precedes its children).
        let parent = copc_lod::nearest_ancestor(n.key, &index);
        taken[i] = ready(n) && parent.is_none_or(|p| taken[p]);
    }
    let nodes: Vec<Node> = cut
        .nodes
        .iter()
        .zip(&taken)
        .filter(|(_, t)| **t)
        .map(|(n, _)| *n)
        .collect();
    Cut {
        points: nodes.iter().map(|n| n.points).sum(),
        deepest: nodes.iter().map(|n| n.key[0]).max().unwrap_or(0),
        nodes,
        ..cut.clone()
    }
}

/// The cloud of `cut`'s nodes (framed by the file's bounds: every budget places it
/// alike) and what it holds; `held`: how many of its nodes were held decoded before the
/// cut was loaded (else those its build found held).
fn cloud_of(c: &Copc, cut: &Cut, held: Option<usize>) -> Result<(PointCloud, Loaded), PointsError> {
    let (cloud, cached) = lasfile::copc_cloud(c, &cut.nodes, cut.root_stride)?;
    let cached = held.unwrap_or(cached);
    let deepest = c.info.spacing / f64::from(1u32 << cut.deepest.clamp(0, 30));
    let spacings = copc_lod::spacings(c, cut, (0..cloud.len()).filter_map(|i| cloud.original(i)));
    // The cloud holds the nodes in the cut's order; a lone root thinned to a stride is
    // all of it (several thinned nodes: no node cache).
    let nodes = if cut.root_stride > 1 {
        match cut.nodes.as_slice() {
            [root] => vec![(root.key, cloud.len())],
            _ => Vec::new(),
        }
    } else {
        cut.nodes
            .iter()
            .map(|n| (n.key, n.points as usize))
            .collect()
    };
    let loaded = Loaded {
        nodes,
        spacing: deepest * (cut.root_stride as f64).sqrt() / cloud.scale,
        size_scales: spacings
            .iter()
            .map(|s| (*s as f64 / deepest) as f32)
            .collect(),
        describe: format!(
            "{}; {cached} of its {} nodes from memory",
            cut.describe(c),
            cut.nodes.len()
        ),
    };
    Ok((cloud, loaded))
}
