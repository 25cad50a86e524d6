//! Whole remote objects (a store's metadata and chunks): one GET each, no HEAD before it;
//! kept in memory (up to 256 MiB) and on disk ([`super::cache`]); fetched ahead many at a
//! time ([`prefetch`]) with a reader that asks for one in flight waiting for it, not
//! fetching it twice. An object on disk is used without a request once this process has
//! seen its ETag; before that, one `If-None-Match` request asks whether it still holds (a
//! 304 carries no bytes).

use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Condvar, Mutex, OnceLock};

use futures::StreamExt;
use object_store::GetOptions;

use super::client::{self, Object};
use super::{count, FetchError, WHOLE};

/// What a read of a whole object found: its bytes, or that it is absent (404).
pub type Found = Option<Arc<Vec<u8>>>;

type Outcome = Result<Found, FetchError>;

/// A fetch under way: its outcome, once there.
#[derive(Default)]
struct Slot {
    outcome: Mutex<Option<Outcome>>,
    done: Condvar,
}

#[derive(Default)]
struct Memory {
    objects: HashMap<String, Found>,
    order: VecDeque<String>,
    bytes: u64,
    pending: HashMap<String, Arc<Slot>>,
}

const MEMORY_BYTES: u64 = 256 << 20;

fn memory() -> std::sync::MutexGuard<'static, Memory> {
    static MEMORY: OnceLock<Mutex<Memory>> = OnceLock::new();
    MEMORY
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner())
}

impl Memory {
    fn keep(&mut self, url: &str, found: &Found) {
        if self.objects.contains_key(url) {
            return;
        }
        self.bytes += found.as_ref().map_or(0, |b| b.len() as u64);
        self.objects.insert(url.to_string(), found.clone());
        self.order.push_back(url.to_string());
        while self.bytes > MEMORY_BYTES {
            let Some(old) = self.order.pop_front() else {
                break;
            };
            if let Some(Some(b)) = self.objects.remove(&old) {
                self.bytes -= b.len() as u64;
            }
        }
    }
}

/// The object at `url`, at most `max` bytes.
pub fn read(url: &str, max: u64) -> Outcome {
    let slot = {
        let mut m = memory();
        if let Some(found) = m.objects.get(url) {
            return Ok(found.clone());
        }
        match m.pending.get(url) {
            Some(slot) => Some(slot.clone()),
            None => {
                m.pending.insert(url.to_string(), Arc::new(Slot::default()));
                None
            }
        }
    };
    if let Some(slot) = slot {
        // Fetched ahead: wait for it.
        let mut outcome = slot.outcome.lock().unwrap_or_else(|e| e.into_inner());
        while outcome.is_none() {
            outcome = slot.done.wait(outcome).unwrap_or_else(|e| e.into_inner());
        }
        return outcome.clone().expect("a finished fetch");
    }
    let outcome = match client::object(url) {
        Ok(object) => client::runtime().block_on(fetch(object, max)),
        Err(e) => Err(e),
    };
    finish(url, &outcome);
    outcome
}

/// Whether the object at `url` is there (a HEAD request).
pub fn head(url: &str) -> bool {
    let Ok(object) = client::object(url) else {
        return false;
    };
    let _busy = count::request();
    client::runtime()
        .block_on(object_store::ObjectStoreExt::head(
            &*object.store,
            &object.path,
        ))
        .is_ok()
}

/// Start fetching `stages` without waiting: each stage's objects many at a time, in
/// order, and a stage only once the one before it is in (the coarse levels of a view
/// before the finer ones).
pub fn prefetch(stages: Vec<Vec<String>>) {
    let mut started: Vec<Vec<String>> = Vec::new();
    {
        let mut m = memory();
        for stage in stages {
            let mut urls = Vec::new();
            for url in stage {
                if m.objects.contains_key(&url) || m.pending.contains_key(&url) {
                    continue;
                }
                m.pending.insert(url.clone(), Arc::new(Slot::default()));
                urls.push(url);
            }
            if !urls.is_empty() {
                started.push(urls);
            }
        }
    }
    if started.is_empty() {
        return;
    }
    let limit = client::in_flight();
    client::runtime().spawn(async move {
        for stage in started {
            futures::stream::iter(stage)
                .map(|url| async move {
                    // One queue for every prefetch, first come first served: the bricks
                    // a loader reads next go before those it reads later.
                    let _permit = permits().acquire().await;
                    let outcome = match client::object(&url) {
                        Ok(object) => fetch(object, super::zarr_max()).await,
                        Err(e) => Err(e),
                    };
                    finish(&url, &outcome);
                })
                .buffered(limit)
                .for_each(|_| async {})
                .await;
        }
    });
}

/// The prefetches' requests in flight, at most [`client::in_flight`] of them together.
fn permits() -> &'static tokio::sync::Semaphore {
    static PERMITS: OnceLock<tokio::sync::Semaphore> = OnceLock::new();
    PERMITS.get_or_init(|| tokio::sync::Semaphore::new(client::in_flight()))
}

/// Hand `outcome` to whoever waits for `url`, and keep it.
fn finish(url: &str, outcome: &Outcome) {
    let slot = {
        let mut m = memory();
        if let Ok(found) = outcome {
            m.keep(url, found);
        }
        m.pending.remove(url)
    };
    if let Some(slot) = slot {
        *slot.outcome.lock().unwrap_or_else(|e| e.into_inner()) = Some(outcome.clone());
        slot.done.notify_all();
    }
}

/// One GET of the whole object (conditional on the ETag of the bytes on disk, if any),
/// within the request deadline.
async fn fetch(object: Object, max: u64) -> Outcome {
    let url = object.url.clone();
    client::within(&url, None, fetch_unbounded(object, max)).await
}

/// [`fetch`] with no deadline of its own.
async fn fetch_unbounded(object: Object, max: u64) -> Outcome {
    let disk = super::cache::global().and_then(|c| c.get(&object.url, &WHOLE));
    let known = super::known_etag(&object.url);
    if let (Some(entry), Some(etag)) = (&disk, &known) {
        if &entry.etag == etag {
            count::from_disk(entry.bytes.len());
            return Ok(Some(Arc::new(entry.bytes.clone())));
        }
    }
    let options = GetOptions {
        if_none_match: disk.as_ref().map(|e| e.etag.clone()),
        ..Default::default()
    };
    let _busy = count::request();
    let got = match object.store.get_opts(&object.path, options).await {
        Ok(got) => got,
        Err(object_store::Error::NotModified { .. }) if disk.is_some() => {
            let entry = disk.expect("checked");
            super::learn_etag(&object.url, &entry.etag, entry.size)?;
            count::from_disk(entry.bytes.len());
            return Ok(Some(Arc::new(entry.bytes)));
        }
        Err(object_store::Error::NotFound { .. }) => return Ok(None),
        Err(e) => return Err(client::failure(&object, None, &e)),
    };
    let size = got.meta.size;
    if size > max {
        return Err(FetchError::TooLarge { bytes: size, max });
    }
    let etag = got.meta.e_tag.clone();
    let mut body = got.into_stream();
    let mut bytes = Vec::with_capacity(size as usize);
    while let Some(part) = body.next().await {
        let part = part.map_err(|e| client::failure(&object, None, &e))?;
        if (bytes.len() + part.len()) as u64 > size {
            return Err(FetchError::at(
                &object.url,
                None,
                format!("the server sent more than the {size} bytes it announced"),
            ));
        }
        bytes.extend_from_slice(&part);
        count::fetched(part.len());
    }
    if (bytes.len() as u64) < size {
        return Err(FetchError::at(
            &object.url,
            None,
            format!("the body ended after {} of its {size} bytes", bytes.len()),
        ));
    }
    if let Some(etag) = &etag {
        super::learn_etag(&object.url, etag, size)?;
        if let Some(c) = super::cache::global() {
            c.put(&object.url, &WHOLE, etag, size, &bytes);
        }
    }
    Ok(Some(Arc::new(bytes)))
}
