//! A COPC cut loaded for the view the camera stopped at: on a thread, in stages
//! ([`arbvis_data::points::copc_load`]), which the renderer takes one a frame; a loading dropped
//! (the camera moved on) stops its thread before the next batch.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, TryRecvError};
use std::sync::Arc;

use crate::error::{RenderError, RenderResult};
use crate::techniques::splats::prepare::prepare_in_stages;
use crate::techniques::splats::scene::SplatsScene;
use arbvis_data::points::copc_load::Stages;
use arbvis_data::points::copc_lod::View as CloudView;

/// What [`prepare_for`](crate::techniques::splats::prepare::prepare_for) makes.
pub(super) type Prepared3 = crate::techniques::splats::prepare::PreparedCloud;

/// A COPC cut being loaded on a thread for a view.
pub(super) struct Loading {
    /// The view it is loaded for.
    pub(super) view: CloudView,
    /// The settings the cut is prepared with (an edit meanwhile prepares it again).
    pub(super) params: SplatsScene,
    /// Its stages (each prepared, and whether it is the whole cut), or why it failed.
    result: Receiver<RenderResult<(Prepared3, bool)>>,
    /// Set when this loading is dropped: the loader stops before its next batch.
    stop: Arc<AtomicBool>,
}

/// What a loading has for the renderer now.
pub(super) enum Arrival {
    /// Nothing yet.
    Waiting,
    /// A stage, and whether it is the whole cut.
    Stage(Box<Prepared3>, bool),
    /// The cut cannot be loaded (a damaged node, say).
    Failed(RenderError),
    /// The loader ended without the whole cut (it panicked).
    Ended,
}

impl Loading {
    /// Start loading `params`' cloud (relative paths from `base`) for `view` in `stages`.
    pub(super) fn start(
        view: CloudView,
        params: SplatsScene,
        base: PathBuf,
        stages: &Stages,
    ) -> Loading {
        let (send, result) = std::sync::mpsc::channel();
        let stop = Arc::new(AtomicBool::new(false));
        let stages = Stages {
            stop: Some(stop.clone()),
            ..stages.clone()
        };
        let prepared_with = params.clone();
        std::thread::spawn(move || {
            let done = prepare_in_stages(&params, &base, &view, stages, |stage, whole| {
                send.send(Ok((stage, whole))).is_ok()
            });
            if let Err(e) = done {
                let _ = send.send(Err(e));
            }
        });
        Loading {
            view,
            params: prepared_with,
            result,
            stop,
        }
    }

    /// The next thing that has arrived (one stage at a time, in order).
    pub(super) fn poll(&self) -> Arrival {
        match self.result.try_recv() {
            Ok(Ok((stage, whole))) => Arrival::Stage(Box::new(stage), whole),
            Ok(Err(e)) => Arrival::Failed(e),
            Err(TryRecvError::Empty) => Arrival::Waiting,
            Err(TryRecvError::Disconnected) => Arrival::Ended,
        }
    }
}

impl Drop for Loading {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
    }
}

/// A cut's line (`cut`) kept when its view is not refined, saying `why`: a stage's
/// progress and an earlier reason dropped.
pub(super) fn not_refined(cut: &str, why: &str) -> String {
    let kept = cut.split("\nnot refined: ").next().unwrap_or("");
    let kept = match kept.split_once("; loading: ") {
        Some((head, tail)) => format!("{head}{}", tail.find("; ").map_or("", |k| &tail[k..])),
        None => kept.to_string(),
    };
    format!("{kept}\nnot refined: {why}")
}

#[cfg(test)]
mod tests {
    use super::not_refined;

    #[test]
    fn a_line_not_refined_drops_its_progress_and_the_last_reason() {
        let line = "COPC: 3 of 9 nodes; 1 of its 3 nodes from memory; loading: 3 of the view's 9 nodes; splats of point size 4.0";
        assert_eq!(
            not_refined(line, "node [3, 1, 0, 2]: bad"),
            "COPC: 3 of 9 nodes; 1 of its 3 nodes from memory; splats of point size 4.0\nnot refined: node [3, 1, 0, 2]: bad"
        );
        let twice = not_refined(&not_refined(line, "a"), "b");
        assert!(twice.ends_with("4.0\nnot refined: b"), "{twice}");
    }
}
