//! Stores and COPC clouds read over HTTP and S3, against loopback servers the tests start
//! and stop (`common::serve`): a remote render equals the local one bit for bit, a
//! second render fetches no bytes (the disk cache, revalidated with `If-None-Match`),
//! a first picture's requests are counted, and every fault either is survived (retries)
//! or ends in an error naming the URL and what went wrong, never a hang.
//!
//! Each render or inspect is a process of its own, with its own cache folder
//! (`ARBVIS_CACHE_DIR`), so no test shares a cache or a client with another.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use crate::common::serve::Server;
use crate::common::{data_file, temp_dir};

/// `arbvis ARGS` with the cache in `cache` and `env` set.
pub(crate) fn arbvis(args: &[&str], cache: &Path, env: &[(&str, &str)]) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_arbvis"));
    c.args(args)
        .env("ARBVIS_CACHE_DIR", cache)
        .env_remove("AWS_ACCESS_KEY_ID")
        .env_remove("AWS_ENDPOINT_URL");
    for (k, v) in env {
        c.env(k, v);
    }
    c.output().unwrap()
}

pub(crate) fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Render `scene` (a TOML file) to `png`, which must succeed; returns the pixels and
/// what the process says it fetched (requests, bytes, bytes from the disk cache).
fn render(scene: &Path, png: &Path, cache: &Path, env: &[(&str, &str)]) -> (Vec<u8>, Fetched) {
    let out = arbvis(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ],
        cache,
        env,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let (image, _) = arbvis::png_io::read_png(png).unwrap();
    (image.to_rgba8(), fetched(&stderr(&out)))
}

/// Requests, bytes fetched and bytes from the disk cache.
type Fetched = (u64, u64, u64);

/// The `fetched: N requests, X MB; Y MB from the disk cache` line of a process's stderr
/// (bytes to 10 kB); zeros when it fetched nothing.
fn fetched(text: &str) -> Fetched {
    let Some(line) = text.lines().find(|l| l.starts_with("fetched: ")) else {
        return (0, 0, 0);
    };
    let words: Vec<&str> = line.split_whitespace().collect();
    let mb = |w: &str| (w.parse::<f64>().unwrap() * 1e6).round() as u64;
    (words[1].parse().unwrap(), mb(words[3]), mb(words[5]))
}

/// A converted survey (several bricks and levels, with envelope) in `dir/s.zarr`.
fn store_fixture(name: &str) -> PathBuf {
    let (dir, _) = crate::store::fixture(name, [37, 29, 45], 16);
    dir
}

/// The store tests' scene (amplitude and envelope) of the store `store` (a path or URL)
/// at 64², written to `dir/name`.
fn store_scene(dir: &Path, name: &str, store: &str) -> PathBuf {
    let volume = format!("{{ store = \"{store}\" }}");
    let path = dir.join(name);
    std::fs::write(&path, crate::store::store_scene_text(&volume, "", 64)).unwrap();
    path
}

/// The autzen scene's splats on the COPC cloud `copc` (a path or URL) at 96 x 72.
pub(crate) fn copc_scene(dir: &Path, name: &str, copc: &str) -> PathBuf {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/data/autzen.toml"),
    )
    .unwrap()
    .replace(
        r#"cloud = { las = "../../data/points/autzen_trim.laz" }"#,
        &format!(r#"cloud = {{ copc = {{ path = "{copc}", points = 100000 }} }}"#),
    )
    .replace("size = [", "size = [96, 72]\n# was [");
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A COPC cloud of many nodes (autzen_trim.laz, 110,000 points, written by `arbvis
/// convert` with nodes of at most 2,000 points: 43 nodes, 941 KiB) as `dir/c.copc.laz`.
pub(crate) fn copc_fixture(dir: &Path) {
    let out = Command::new(env!("CARGO_BIN_EXE_arbvis"))
        .arg("convert")
        .arg(data_file("points/autzen_trim.laz"))
        .arg(dir.join("c.copc.laz"))
        .args(["--node-points", "2000"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
}

/// A test folder `name` holding [`copc_fixture`]'s cloud, the HTTP server on it, and the
/// folder's cache path.
pub(crate) fn copc_served(name: &str) -> (PathBuf, Server, PathBuf) {
    let dir = temp_dir(name);
    copc_fixture(&dir);
    let server = Server::http(&dir);
    let cache = dir.join("cache");
    (dir, server, cache)
}

/// Bytes of every file under `dir`.
fn bytes_under(dir: &Path) -> u64 {
    let mut total = 0;
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let m = e.metadata().unwrap();
        total += if m.is_dir() {
            bytes_under(&e.path())
        } else {
            m.len()
        };
    }
    total
}

/// A store over HTTP: the same picture as from disk, its bytes fetched at most once
/// (the first picture fetches no more than the store holds, and a second process with
/// the same cache fetches none: every object revalidated by a 304); two processes
/// sharing one cache at once both draw it; `convert` from the URL makes the store that
/// `convert` from the folder makes.
#[test]
fn a_store_over_http_renders_as_the_local_one_and_then_from_the_cache() {
    let dir = store_fixture("remote-store-http");
    let server = Server::http(&dir);
    let local = store_scene(&dir, "local.toml", "s.zarr");
    let remote = store_scene(&dir, "remote.toml", &server.url("s.zarr"));
    let cache = dir.join("cache");
    let (want, none) = render(&local, &dir.join("local.png"), &cache, &[]);
    assert_eq!(none, (0, 0, 0), "a local store fetches nothing");
    let (got, (requests, bytes, _)) = render(&remote, &dir.join("remote.png"), &cache, &[]);
    assert!(got == want, "the remote picture differs from the local one");
    let (server_requests, server_bytes) = server.counts();
    assert_eq!(requests, server_requests, "every request counted");
    let store_bytes = bytes_under(&dir.join("s.zarr"));
    assert!(
        server_bytes <= store_bytes && bytes.abs_diff(server_bytes) <= 5_000,
        "fetched {server_bytes} bytes (reported {bytes}) of a {store_bytes}-byte store"
    );
    // Again, a new process on the same cache: revalidated, no body fetched.
    server.control("_reset");
    let (again, (requests_again, ..)) = render(&remote, &dir.join("again.png"), &cache, &[]);
    assert!(again == want);
    let (_, body) = server.counts();
    assert_eq!(body, 0, "{requests_again} requests, all answered 304");
    // Two processes on one cache at once.
    let shared = dir.join("shared-cache");
    let run = |png: &str| {
        let (remote, png, shared) = (remote.clone(), dir.join(png), shared.clone());
        std::thread::spawn(move || render(&remote, &png, &shared, &[]).0)
    };
    let (a, b) = (run("a.png"), run("b.png"));
    assert!(a.join().unwrap() == want && b.join().unwrap() == want);
    // `convert` reads a remote dataset (the store as an MDIO dataset) as a local one.
    let convert = |from: &str, to: &str| {
        let out = arbvis(
            &["convert", from, dir.join(to).to_str().unwrap()],
            &cache,
            &[],
        );
        assert!(out.status.success(), "{}", stderr(&out));
        crate::store::all_values(&arbvis::store::Store::open(&dir.join(to)).unwrap())
    };
    let local = convert(dir.join("s.zarr").to_str().unwrap(), "from-local.zarr");
    assert!(convert(&server.url("s.zarr"), "from-remote.zarr") == local);
}

/// A COPC cloud over HTTP: the same picture as from disk; the first picture's requests
/// are the header block, the hierarchy and the nodes' ranges merged, its bytes at most
/// twice what the picture reads; a second process with the same cache fetches no bytes.
#[test]
fn a_copc_cloud_over_http_renders_as_the_local_one_in_few_requests() {
    let (dir, server, cache) = copc_served("remote-copc-http");
    let local = copc_scene(&dir, "local.toml", "c.copc.laz");
    let remote = copc_scene(&dir, "remote.toml", &server.url("c.copc.laz"));
    let (want, _) = render(&local, &dir.join("local.png"), &cache, &[]);
    let (got, (requests, _, _)) = render(&remote, &dir.join("remote.png"), &cache, &[]);
    assert!(got == want, "the remote picture differs from the local one");
    let (server_requests, server_bytes) = server.counts();
    assert_eq!(requests, server_requests);
    // The first 64 KiB block (header, VLRs), the block of the hierarchy at the file's
    // end, and the view's nodes (most of the 43) in ranges merged across gaps under
    // 32 KiB: 6 requests here, where one per node would be over 40.
    assert!(requests <= 8, "{requests} requests");
    server.control("_reset");
    let (again, (_, _, read)) = render(&remote, &dir.join("again.png"), &cache, &[]);
    assert!(again == want);
    assert_eq!(server.counts().1, 0, "the second picture fetched bytes");
    // What the second picture read from the disk cache is what a picture reads: the
    // first fetched at most twice that (gaps merged over, blocks rounded out).
    assert!(
        server_bytes <= 2 * read + 10_000,
        "fetched {server_bytes} bytes for a picture that reads {read}"
    );
}

/// The same store and cloud from moto's S3 server (`s3://BUCKET/KEY`, the endpoint and
/// keys as AWS's tools take them): equal to the local pictures.
#[test]
fn a_store_and_a_copc_cloud_on_s3_render_as_the_local_ones() {
    let dir = store_fixture("remote-s3");
    copc_fixture(&dir);
    let cache = dir.join("cache");
    let (want_store, _) = render(
        &store_scene(&dir, "local.toml", "s.zarr"),
        &dir.join("local.png"),
        &cache,
        &[],
    );
    let (want_copc, _) = render(
        &copc_scene(&dir, "local-copc.toml", "c.copc.laz"),
        &dir.join("local-copc.png"),
        &cache,
        &[],
    );
    let upload = temp_dir("remote-s3-bucket");
    crate::common::copy_tree(&dir.join("s.zarr"), &upload.join("surveys/s.zarr"));
    std::fs::copy(dir.join("c.copc.laz"), upload.join("c.copc.laz")).unwrap();
    let Some(server) = Server::s3("arbvis-test", &upload) else {
        return;
    };
    let endpoint = format!("http://127.0.0.1:{}", server.port);
    let env = [
        ("AWS_ENDPOINT_URL", endpoint.as_str()),
        ("AWS_ACCESS_KEY_ID", "test"),
        ("AWS_SECRET_ACCESS_KEY", "test"),
        ("AWS_REGION", "us-east-1"),
    ];
    let s3_cache = dir.join("s3-cache");
    let scene = store_scene(&dir, "s3.toml", "s3://arbvis-test/surveys/s.zarr");
    let (got, (requests, ..)) = render(&scene, &dir.join("s3.png"), &s3_cache, &env);
    assert!(got == want_store, "the S3 store's picture differs");
    assert!(requests > 0);
    let scene = copc_scene(&dir, "s3-copc.toml", "s3://arbvis-test/c.copc.laz");
    let (got, _) = render(&scene, &dir.join("s3-copc.png"), &s3_cache, &env);
    assert!(got == want_copc, "the S3 cloud's picture differs");
    // `inspect` reads the URL too.
    let out = arbvis(&["inspect", "s3://arbvis-test/c.copc.laz"], &s3_cache, &env);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("COPC octree"), "{text}");
    // A missing object is a 404 naming it.
    let out = arbvis(
        &["inspect", "s3://arbvis-test/none.copc.laz"],
        &s3_cache,
        &env,
    );
    let e = crate::common::refused(&out, "s3://arbvis-test/none.copc.laz");
    assert!(e.contains("404"), "{e}");
}

/// `arbvis inspect URL` of the COPC file with fault `mode` injected for `count` requests
/// (0: all) after `skip` good ones: its output, and how long it took.
fn inspect_with_fault(
    server: &Server,
    cache: &Path,
    mode: &str,
    count: u32,
    skip: u32,
) -> (Output, Duration) {
    server.control(&format!("_fault?mode={mode}&count={count}&skip={skip}"));
    let t = Instant::now();
    let out = arbvis(
        &["inspect", &server.url("c.copc.laz")],
        cache,
        &[("ARBVIS_REMOTE_TIMEOUT", "1")],
    );
    server.control("_reset");
    (out, t.elapsed())
}

/// Faults: 503s, a 429, a dropped connection and a body cut off are retried and
/// survived; a stalled server, a refusal (403), a server ignoring `Range`, a short body
/// and a file that changes while it is read are errors naming the URL (and the byte
/// range or the variables to set), within seconds. No fault leaves a wrong entry in the
/// cache: a clean inspect afterwards says what the first one said. A node's range that
/// fails is an error naming the node.
#[test]
fn faults_are_retried_or_named_never_waited_on() {
    let (dir, server, cache) = copc_served("remote-faults");
    let clean = inspect_with_fault(&server, &cache, "none", 0, 0).0;
    assert!(clean.status.success(), "{}", stderr(&clean));
    for (mode, count) in [
        ("status:503", 2),
        ("status:429", 1),
        ("reset", 1),
        ("truncate", 1),
    ] {
        // Each with a cache of its own: every read goes to the server.
        let cache = dir.join(format!("cache-{}", mode.replace(':', "-")));
        let (out, _) = inspect_with_fault(&server, &cache, mode, count, 0);
        assert!(out.status.success(), "{mode}: {}", stderr(&out));
        assert_eq!(out.stdout, clean.stdout, "{mode}");
    }
    let url = server.url("c.copc.laz");
    let refusals: [(&str, u32, &[&str]); 6] = [
        ("stall", 0, &["bytes 0-65535"]),
        ("status:403", 0, &["403", "AWS_ACCESS_KEY_ID"]),
        ("status:401", 0, &["401", "AWS_SECRET_ACCESS_KEY"]),
        ("ignore-range", 0, &["ignored the Range request"]),
        ("short", 0, &["the body held"]),
        ("change", 0, &["changed while it was read"]),
    ];
    for (mode, skip, says) in refusals {
        let cache = dir.join(format!("cache-{}", mode.replace(':', "-")));
        // The change comes after the first request (the file opened, then rewritten).
        let skip = if mode == "change" { 1 } else { skip };
        let (out, took) = inspect_with_fault(&server, &cache, mode, 0, skip);
        let e = stderr(&out);
        assert!(!out.status.success(), "{mode}: succeeded");
        assert!(e.contains(&url), "{mode}: the URL unnamed: {e}");
        for s in says {
            assert!(e.contains(s), "{mode}: {s:?} unsaid: {e}");
        }
        // A stall: the 1 s timeout, retried up to twice the timeout; the others at once
        // (a few backoffs of at most 2 s).
        assert!(took < Duration::from_secs(20), "{mode}: {took:?}");
    }
    let after = inspect_with_fault(&server, &cache, "none", 0, 0).0;
    assert_eq!(after.stdout, clean.stdout);
    // A node whose range is refused, once the header and hierarchy are read: the error
    // names the node and the URL.
    server.control("_fault?mode=status:403&count=0&skip=2");
    let scene = copc_scene(&dir, "remote.toml", &url);
    let out = arbvis(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            dir.join("x.png").to_str().unwrap(),
        ],
        &dir.join("cache-nodes"),
        &[],
    );
    let e = stderr(&out);
    assert!(!out.status.success(), "a refused node drew a picture");
    for s in [url.as_str(), "node [", "points,", "403"] {
        assert!(e.contains(s), "{s:?} unsaid: {e}");
    }
}

/// A store's chunk absent on the server (404) is what an absent file is: here a chunk
/// whose brick ranges say it holds values, so both reads refuse it with the same words.
#[test]
fn an_absent_chunk_over_http_is_an_absent_file() {
    let dir = store_fixture("remote-absent");
    let chunk = dir.join("s.zarr/amplitude/c/1/0/1");
    std::fs::remove_file(&chunk).expect("the fixture has chunk 1/0/1");
    let server = Server::http(&dir);
    let cache = dir.join("cache");
    let say = |store: &str, name: &str| {
        let out = arbvis(
            &[
                "render",
                store_scene(&dir, name, store).to_str().unwrap(),
                "-o",
                dir.join("x.png").to_str().unwrap(),
            ],
            &cache,
            &[],
        );
        assert!(!out.status.success());
        let e = stderr(&out);
        e.lines()
            .find(|l| l.contains("missing, but the store's ranges"))
            .unwrap_or_else(|| panic!("{e}"))
            .replace(&server.url(""), "")
            .replace(&format!("{}/", dir.display()), "")
    };
    assert_eq!(
        say("s.zarr", "local.toml"),
        say(&server.url("s.zarr"), "remote.toml").replace("remote.toml", "local.toml")
    );
}
