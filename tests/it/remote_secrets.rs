//! Remote data against hostile servers, round 5: a URL's secrets never leave the process
//! but in the request to their own host (not in errors, `inspect`, the disk cache or the
//! PNG's scene text; a session token is not sent on a redirect to another host), and a
//! body is never buffered past the range asked for, whatever length the server declares.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::common::serve::Server;
use super::remote::{arbvis, copc_scene, copc_served, stderr};

/// Every file's bytes under `dir`, joined (to look for a secret anywhere in them).
fn all_bytes(dir: &Path) -> Vec<u8> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(all_bytes(&p));
        } else {
            out.extend(std::fs::read(&p).unwrap_or_default());
        }
    }
    out
}

fn holds(bytes: &[u8], secret: &str) -> bool {
    bytes.windows(secret.len()).any(|w| w == secret.as_bytes())
}

/// Render the autzen splats scene on the COPC cloud at `url` to `DIR/NAME.png`: the
/// process's output and the picture's path.
fn render_cloud(
    dir: &Path,
    name: &str,
    url: &str,
    cache: &Path,
) -> (std::process::Output, PathBuf) {
    let scene = copc_scene(dir, &format!("{name}.toml"), url);
    let png = dir.join(format!("{name}.png"));
    let args = [
        "render",
        scene.to_str().unwrap(),
        "-o",
        png.to_str().unwrap(),
    ];
    (arbvis(&args, cache, &[]), png)
}

/// A password in the URL reaches the server (as HTTP basic authentication) and nothing
/// else: not `inspect`'s text, not an error line, not a cache entry, not the PNG.
#[test]
fn a_urls_password_stays_out_of_inspect_errors_the_cache_and_the_png() {
    let (dir, server, cache) = copc_served("remote-secrets");
    let secret = "hunter2-secret";
    let url = format!("http://me:{secret}@127.0.0.1:{}/c.copc.laz", server.port);
    let out = arbvis(&["inspect", &url], &cache, &[]);
    let said = String::from_utf8_lossy(&out.stdout).into_owned() + &stderr(&out);
    assert!(out.status.success(), "{said}");
    assert!(!said.contains(secret) && said.contains("me:***@"), "{said}");
    let stats = server.control("_stats");
    assert!(
        !stats.contains("\"authorized\": 0"),
        "no credentials sent: {stats}"
    );
    // A refusal: the error names the URL, its password hidden.
    server.control("_fault?mode=status:403&count=0&skip=0");
    let out = arbvis(&["inspect", &url], &dir.join("cache-refused"), &[]);
    let e = crate::common::refused(&out, "403");
    assert!(!e.contains(secret) && e.contains("me:***@127.0.0.1"), "{e}");
    server.control("_reset");
    // A picture: the scene text it embeds names the URL without the password.
    let (out, png) = render_cloud(&dir, "secret", &url, &cache);
    assert!(out.status.success(), "{}", stderr(&out));
    let (_, text) = arbvis::png_io::read_png(&png).unwrap();
    let embedded: String = text.iter().map(|(k, v)| format!("{k}: {v}\n")).collect();
    assert!(embedded.contains("me:***@127.0.0.1"), "{embedded}");
    assert!(!embedded.contains(secret), "{embedded}");
    // The cache's entries (the COPC header, hierarchy and nodes) hold no password.
    let cached = all_bytes(&cache);
    assert!(cached.len() > 1000, "the cache was used");
    assert!(!holds(&cached, secret), "a cache entry holds the password");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A signed S3 request redirected (307) to another host is not followed: the session
/// token reaches only the endpoint it was meant for, and the error says why. The same
/// endpoint without the redirect reads the cloud (so the token is sent where it should).
#[test]
fn a_session_token_is_not_sent_to_the_host_a_redirect_names() {
    let (dir, _, cache) = copc_served("remote-token");
    // Path-style S3 requests: /BUCKET/KEY under the endpoint's folder.
    let bucket = dir.join("bkt");
    std::fs::create_dir_all(&bucket).unwrap();
    std::fs::copy(dir.join("c.copc.laz"), bucket.join("c.copc.laz")).unwrap();
    let (endpoint, elsewhere) = (Server::http(&dir), Server::http(&dir));
    let aws = |port: u16| {
        [
            ("AWS_ENDPOINT_URL", format!("http://127.0.0.1:{port}")),
            ("AWS_ACCESS_KEY_ID", "AKIDTEST".to_string()),
            ("AWS_SECRET_ACCESS_KEY", "secretkey".to_string()),
            ("AWS_SESSION_TOKEN", "the-session-token".to_string()),
            ("AWS_REGION", "us-east-1".to_string()),
            ("AWS_ALLOW_HTTP", "true".to_string()),
        ]
    };
    let env = aws(endpoint.port);
    let env: Vec<(&str, &str)> = env.iter().map(|(k, v)| (*k, v.as_str())).collect();
    let ok = arbvis(&["inspect", "s3://bkt/c.copc.laz"], &cache, &env);
    assert!(ok.status.success(), "{}", stderr(&ok));
    let stats = endpoint.control("_stats");
    assert!(!stats.contains("\"tokens\": 0"), "no token sent: {stats}");
    endpoint.control("_reset");
    endpoint.control(&format!(
        "_fault?mode=redirect:{}&count=0&skip=0",
        elsewhere.port
    ));
    let out = arbvis(
        &["inspect", "s3://bkt/c.copc.laz"],
        &dir.join("cache-2"),
        &env,
    );
    let e = stderr(&out);
    assert!(!out.status.success(), "a redirected request succeeded");
    assert!(
        e.contains("another host") && e.contains("s3://bkt/c.copc.laz"),
        "{e}"
    );
    let stats = elsewhere.control("_stats");
    assert!(
        stats.contains("\"tokens\": 0") && stats.contains("\"requests\": 0"),
        "{stats}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A range answered with `Content-Length: 2147483648` (and 2 GiB of zeros behind the
/// range's bytes) is refused once the body passes the range: in seconds, under an
/// address-space limit of 1.5 GiB that buffering the declared body would break.
#[test]
fn a_declared_two_gib_body_is_not_buffered() {
    let (dir, server, cache) = copc_served("remote-huge");
    server.control("_fault?mode=huge&count=0&skip=0");
    let t = Instant::now();
    let out = std::process::Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 1572864 && exec \"$0\" inspect \"$1\"")
        .arg(env!("CARGO_BIN_EXE_arbvis"))
        .arg(server.url("c.copc.laz"))
        .env("ARBVIS_CACHE_DIR", &cache)
        .output()
        .unwrap();
    let e = stderr(&out);
    assert!(!out.status.success(), "a 2 GiB body was taken");
    assert!(
        e.contains("more than the range's") && e.contains("c.copc.laz") && e.contains("bytes 0-"),
        "{e}"
    );
    // Loopback moves 2 GiB in about a second; the refusal comes after the first range.
    assert!(t.elapsed() < Duration::from_secs(30), "{:?}", t.elapsed());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A timeout that cannot be read (`0`, `5s`) is refused by name when a URL is opened,
/// instead of silently meaning 30 s.
#[test]
fn an_unreadable_remote_timeout_is_refused_by_name() {
    let (dir, server, cache) = copc_served("remote-timeout");
    for bad in ["0", "5s", "-1", "nan"] {
        let out = arbvis(
            &["inspect", &server.url("c.copc.laz")],
            &cache,
            &[("ARBVIS_REMOTE_TIMEOUT", bad)],
        );
        let e = stderr(&out);
        assert!(!out.status.success(), "{bad}: accepted");
        assert!(
            e.contains("ARBVIS_REMOTE_TIMEOUT") && e.contains("expected seconds"),
            "{bad}: {e}"
        );
    }
    let out = arbvis(
        &["inspect", &server.url("c.copc.laz")],
        &cache,
        &[("ARBVIS_REMOTE_TIMEOUT", "2.5")],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A server that cannot be reached is said to be so, for a store and a COPC cloud, by
/// `inspect` and by a render: not "no such store".
#[test]
fn an_unreachable_server_is_named_as_such() {
    let dir = super::common::temp_dir("remote-unreachable");
    // A port that was free a moment ago: nothing listens there.
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let cache = dir.join("cache");
    let env = [("ARBVIS_REMOTE_TIMEOUT", "1")];
    for name in ["s.zarr", "c.copc.laz"] {
        let url = format!("http://127.0.0.1:{port}/{name}");
        let out = arbvis(&["inspect", &url], &cache, &env);
        let e = stderr(&out);
        assert!(!out.status.success(), "{name}");
        assert!(
            e.contains(&url) && e.contains("could not be reached"),
            "{e}"
        );
        assert!(!e.contains("no such store"), "{e}");
    }
    let store = format!("http://127.0.0.1:{port}/s.zarr");
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        format!("[technique.opacity3d.primary]\nvolume = {{ store = \"{store}\" }}\nattribute = \"amplitude\"\n"),
    )
    .unwrap();
    let png = dir.join("s.png");
    let out = arbvis(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
        ],
        &cache,
        &env,
    );
    crate::common::refused(&out, "could not be reached");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A pre-signed (or tokened) URL of a COPC file: its query goes with every request (the
/// server refuses any request without it), and its secret values appear nowhere arbvis
/// writes; a query in a store's (folder's) URL is refused by name.
#[test]
fn a_pre_signed_urls_query_goes_with_every_request_and_nowhere_else() {
    let (dir, server, cache) = copc_served("remote-presigned");
    let query = "X-Amz-Credential=AKID%2F20261207&X-Amz-Signature=0badc0ffee";
    server.control(&format!(
        "_fault?mode=need-query:{}&count=0&skip=0",
        query.replace('%', "%25").replace('&', "%26")
    ));
    let url = format!("{}?{query}", server.url("c.copc.laz"));
    let out = arbvis(&["inspect", &url], &cache, &[]);
    let said = String::from_utf8_lossy(&out.stdout).into_owned() + &stderr(&out);
    assert!(out.status.success(), "{said}");
    assert!(
        !said.contains("0badc0ffee") && !said.contains("AKID"),
        "{said}"
    );
    // A render: every node's range request carried the query too.
    let (out, _) = render_cloud(&dir, "signed", &url, &cache);
    assert!(out.status.success(), "{}", stderr(&out));
    let stats = server.control("_stats");
    assert!(!stats.contains("\"requests\": 0"), "{stats}");
    // Without the query, the same server refuses.
    let out = arbvis(
        &["inspect", &server.url("c.copc.laz")],
        &dir.join("c2"),
        &[],
    );
    assert!(
        !out.status.success() && stderr(&out).contains("403"),
        "{}",
        stderr(&out)
    );
    server.control("_reset");
    let store = format!("{}?token=abc", server.url("s.zarr"));
    let out = arbvis(&["inspect", &store], &cache, &[]);
    let e = crate::common::refused(&out, "a query in a folder's URL");
    assert!(!e.contains("abc"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A server that sends weak ETags (nginx for what it may compress) is read (the ETag is
/// compared on each answer instead of sent in If-Match, which a weak one never matches);
/// a stalled server is given up on within twice the timeout, retries included.
#[test]
fn weak_etags_are_read_and_a_stall_ends_within_twice_the_timeout() {
    let (dir, server, cache) = copc_served("remote-weak");
    server.control("_fault?mode=weak-etag&count=0&skip=0");
    let (out, _) = render_cloud(&dir, "weak", &server.url("c.copc.laz"), &cache);
    assert!(out.status.success(), "{}", stderr(&out));
    server.control("_reset");
    // Every request stalls (60 s): at a 2 s timeout, the first one ends by 4 s.
    server.control("_fault?mode=stall&count=0&skip=0");
    let t = Instant::now();
    let out = arbvis(
        &["inspect", &server.url("c.copc.laz")],
        &dir.join("cache-stall"),
        &[("ARBVIS_REMOTE_TIMEOUT", "2")],
    );
    let took = t.elapsed();
    let e = stderr(&out);
    assert!(!out.status.success(), "{e}");
    // 4 s, and what starting the process and its runtime takes on a loaded machine.
    assert!(took < Duration::from_secs(8), "{took:?}: {e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A store's metadata that cannot be read is never "no such store": a 403 names the
/// credential variables, a 301 (S3's wrong region) the redirect, a redirect loop the
/// loop, TLS with a plain HTTP server or a self-signed certificate the TLS failure, a
/// stall the timeout; each names the URL and ends within seconds.
#[test]
fn a_stores_metadata_that_cannot_be_read_says_why_not_that_it_is_absent() {
    let dir = crate::store::fixture("remote-store-faults", [9, 7, 11], 8).0;
    let server = Server::http(&dir);
    let cache = dir.join("cache");
    let env = [("ARBVIS_REMOTE_TIMEOUT", "1")];
    let port = server
        .url("")
        .trim_end_matches('/')
        .rsplit(':')
        .next()
        .unwrap()
        .to_string();
    let cases: [(String, &str, &[&str]); 5] = [
        ("status:403".into(), "http", &["403", "AWS_ACCESS_KEY_ID"]),
        ("status:301".into(), "http", &["redirect", "AWS_REGION"]),
        (
            format!("redirect:{port}"),
            "http",
            &["redirects did not end"],
        ),
        ("none".into(), "https", &["TLS"]),
        ("stall".into(), "http", &["no answer within"]),
    ];
    for (mode, scheme, says) in cases {
        server.control(&format!("_fault?mode={mode}&count=0&skip=0"));
        let url = server.url("s.zarr").replacen("http", scheme, 1);
        let t = std::time::Instant::now();
        let out = arbvis(&["inspect", &url], &cache, &env);
        let took = t.elapsed();
        server.control("_reset");
        let e = stderr(&out);
        assert!(!out.status.success(), "{mode}: succeeded");
        assert!(e.contains(&url), "{mode}: the URL unnamed: {e}");
        assert!(!e.contains("no such store"), "{mode}: {e}");
        for s in says {
            assert!(e.contains(s), "{mode}: {s:?} unsaid: {e}");
        }
        // The 1 s timeout, retried within twice it; the others at once.
        assert!(took < Duration::from_secs(20), "{mode}: {took:?}");
    }
    // A server whose certificate no one signed: the TLS failure, named.
    let tls = Server::https_self_signed(&dir);
    let url = format!("https://127.0.0.1:{}/s.zarr", tls.port);
    let out = arbvis(&["inspect", &url], &cache, &env);
    let e = stderr(&out);
    assert!(!out.status.success(), "a self-signed server was trusted");
    assert!(
        e.contains(&url) && e.contains("TLS") && e.to_lowercase().contains("certificate"),
        "{e}"
    );
    assert!(!e.contains("no such store"), "{e}");
}
