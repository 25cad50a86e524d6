//! The object-storage clients (Apache Arrow's `object_store`): one per bucket or server,
//! made on first use and kept for the process, on one runtime of their own; the settings
//! (timeouts, retries, credentials) read from the environment, and their errors in words
//! that name the URL, the byte range and, where access is refused, the variables to set.

use std::collections::HashMap;
use std::ops::Range;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

use object_store::aws::AmazonS3Builder;
use object_store::http::HttpBuilder;
use object_store::{BackoffConfig, ClientOptions, ObjectStore, RetryConfig};

use super::FetchError;

/// The environment variables arbvis reads for S3, as AWS's own tools read them.
pub const AWS_VARIABLES: &str = "AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY (and AWS_SESSION_TOKEN for temporary credentials; AWS_REGION, AWS_ENDPOINT_URL for an S3-compatible server)";

/// An object named by a URL: its client and its path there.
#[derive(Clone)]
pub struct Object {
    /// The URL as the user gave it (what errors name).
    pub url: String,
    /// The bucket's or server's client.
    pub store: Arc<dyn ObjectStore>,
    /// The object's path in the bucket or on the server.
    pub path: object_store::path::Path,
    /// An S3 object (else HTTP).
    pub s3: bool,
}

/// The runtime the clients run on: two threads, whatever the cores (requests wait on the
/// network, not on a core).
pub fn runtime() -> &'static tokio::runtime::Runtime {
    static RUNTIME: OnceLock<tokio::runtime::Runtime> = OnceLock::new();
    RUNTIME.get_or_init(|| {
        tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .thread_name("arbvis-fetch")
            .enable_all()
            .build()
            .expect("a tokio runtime (two threads)")
    })
}

/// Seconds a request may take before it fails (`ARBVIS_REMOTE_TIMEOUT`, default 30; a
/// value [`timeout_setting`] refuses is refused when a URL is opened).
pub fn timeout() -> Duration {
    timeout_setting().unwrap_or(Duration::from_secs(30))
}

/// `ARBVIS_REMOTE_TIMEOUT` read: seconds, a number above 0 (up to a day), 30 when unset or
/// empty; anything else (`0`, `5s`, `-1`) is an error that says what is expected.
pub fn timeout_setting() -> Result<Duration, SettingError> {
    let Some(text) = std::env::var("ARBVIS_REMOTE_TIMEOUT")
        .ok()
        .filter(|v| !v.trim().is_empty())
    else {
        return Ok(Duration::from_secs(30));
    };
    match text.trim().parse::<f64>() {
        Ok(secs) if secs.is_finite() && secs > 0.0 && secs <= 86_400.0 => {
            Ok(Duration::from_secs_f64(secs))
        }
        _ => Err(SettingError {
            variable: "ARBVIS_REMOTE_TIMEOUT",
            value: text,
            expected: "seconds, a number above 0 and at most 86400 (e.g. 30 or 2.5), with no unit",
        }),
    }
}

/// An environment variable whose value cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{variable}={value:?}: expected {expected}")]
pub struct SettingError {
    /// The variable.
    pub variable: &'static str,
    /// Its value.
    pub value: String,
    /// What it takes.
    pub expected: &'static str,
}

/// The most one request may take, retries and body included: twice the request
/// timeout, as the documentation promises (object_store's own retry budget could let a
/// stalled request run four times as long).
pub fn request_deadline() -> Duration {
    2 * timeout()
}

/// `request` (for `range` of `url`, `None`: the whole object) within
/// [`request_deadline`], else an error saying how long it waited.
pub async fn within<T>(
    url: &str,
    range: Option<&Range<u64>>,
    request: impl std::future::Future<Output = Result<T, FetchError>>,
) -> Result<T, FetchError> {
    let deadline = request_deadline();
    match tokio::time::timeout(deadline, request).await {
        Ok(done) => done,
        Err(_) => {
            let what = match range {
                Some(r) => format!("bytes {}-{}", r.start, r.end.saturating_sub(1)),
                None => "GET".to_string(),
            };
            let m = format!(
                "{what}: no answer within {:.1} s (twice ARBVIS_REMOTE_TIMEOUT, retries included)",
                deadline.as_secs_f64()
            );
            Err(FetchError::at(url, range, m))
        }
    }
}

/// Requests kept in flight at once (`ARBVIS_REMOTE_REQUESTS`, default 16).
pub fn in_flight() -> usize {
    std::env::var("ARBVIS_REMOTE_REQUESTS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .filter(|v| (1..=256).contains(v))
        .unwrap_or(16)
}

fn options() -> ClientOptions {
    let t = timeout();
    ClientOptions::new()
        .with_timeout(t)
        .with_connect_timeout(t.min(Duration::from_secs(10)))
        .with_allow_http(true)
        .with_pool_max_idle_per_host(64)
}

/// Retries on 429, 5xx and dropped connections: four, backing off from 100 ms up to 2 s,
/// and none after twice the request timeout.
fn retry() -> RetryConfig {
    RetryConfig {
        backoff: BackoffConfig {
            init_backoff: Duration::from_millis(100),
            max_backoff: Duration::from_secs(2),
            base: 2.0,
        },
        max_retries: 4,
        retry_timeout: 2 * timeout(),
    }
}

/// The object at `url` (`s3://bucket/key`, `http://` or `https://`).
pub fn object(url: &str) -> Result<Object, FetchError> {
    let fail = |m: String| FetchError::at(url, None, m);
    let (scheme, rest) = url
        .split_once("://")
        .ok_or_else(|| fail("not a URL".to_string()))?;
    let (authority, key) = rest.split_once('/').unwrap_or((rest, ""));
    if authority.is_empty() || key.is_empty() {
        return Err(fail(format!(
            "a URL names a {} and an object in it",
            if scheme == "s3" { "bucket" } else { "server" }
        )));
    }
    let s3 = match scheme {
        "s3" => true,
        "http" | "https" => false,
        _ => {
            let m = "arbvis reads s3://, http://, https:// and file:// URLs";
            return Err(fail(m.to_string()));
        }
    };
    timeout_setting().map_err(|e| fail(e.to_string()))?;
    // A query (a pre-signed URL's signature, a token) goes with every request for the
    // object, not into its key.
    let (key, query) = match key.split_once('?') {
        Some((_, q)) if q.contains('/') => {
            let m = "a query in a folder's URL: a store is read object by object, and a query (a token, a signature) is kept only for one object's URL (a COPC file)";
            return Err(fail(m.to_string()));
        }
        Some((_, _)) if s3 => {
            let m = "an s3:// URL takes no query: its requests are signed with the AWS variables (a pre-signed URL is an https:// URL)";
            return Err(fail(m.to_string()));
        }
        Some((k, q)) => (k, Some(q)),
        None => (key, None),
    };
    let root = format!("{scheme}://{authority}");
    let store = client(&root, s3, query).map_err(|e| fail(format!("{root}: {e}")))?;
    let path = object_store::path::Path::from_url_path(key)
        .map_err(|e| fail(format!("not an object's path: {e}")))?;
    Ok(Object {
        url: url.to_string(),
        store,
        path,
        s3,
    })
}

fn client(
    root: &str,
    s3: bool,
    query: Option<&str>,
) -> Result<Arc<dyn ObjectStore>, object_store::Error> {
    static CLIENTS: OnceLock<Mutex<HashMap<String, Arc<dyn ObjectStore>>>> = OnceLock::new();
    let mut clients = CLIENTS
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(|e| e.into_inner());
    let id = format!("{root}?{}", query.unwrap_or(""));
    if let Some(c) = clients.get(&id) {
        return Ok(c.clone());
    }
    // The builders' reqwest clients start on the runtime.
    let _guard = runtime().enter();
    let made: Arc<dyn ObjectStore> = if s3 {
        let bucket = &root["s3://".len()..];
        let mut b = AmazonS3Builder::from_env()
            .with_bucket_name(bucket)
            .with_client_options(options())
            .with_retry(retry());
        if std::env::var_os("AWS_REGION").is_none()
            && std::env::var_os("AWS_DEFAULT_REGION").is_none()
        {
            b = b.with_region("us-east-1");
        }
        if anonymous() {
            b = b.with_skip_signature(true);
        } else {
            b = b.with_http_connector(super::connect::SameHostRedirects(timeout()));
        }
        Arc::new(b.build()?)
    } else {
        // A password in the URL goes to its server as Basic authorization, which
        // reqwest drops on a redirect to another host.
        let (plain, auth) = basic_auth(root);
        let mut options = options();
        if let Some(value) = auth {
            let mut headers = reqwest::header::HeaderMap::new();
            headers.insert(reqwest::header::AUTHORIZATION, value);
            options = options.with_default_headers(headers);
        }
        let mut b = HttpBuilder::new();
        if let Some(query) = query {
            b = b.with_http_connector(super::connect::WithQuery(query.to_string(), timeout()));
        }
        Arc::new(
            b.with_url(plain)
                .with_client_options(options)
                .with_retry(retry())
                .build()?,
        )
    };
    clients.insert(id, made.clone());
    Ok(made)
}

/// `root` (`scheme://authority`) without its user info, and the Basic authorization
/// that user info says, where it has one.
fn basic_auth(root: &str) -> (String, Option<reqwest::header::HeaderValue>) {
    use base64::Engine as _;
    let Some((scheme, authority)) = root.split_once("://") else {
        return (root.to_string(), None);
    };
    let Some((user_info, host)) = authority.rsplit_once('@') else {
        return (root.to_string(), None);
    };
    let (user, password) = user_info.split_once(':').unwrap_or((user_info, ""));
    let pair = format!(
        "{}:{}",
        super::percent_decode(user),
        super::percent_decode(password)
    );
    let token = base64::engine::general_purpose::STANDARD.encode(pair);
    let value = reqwest::header::HeaderValue::from_str(&format!("Basic {token}"))
        .ok()
        .map(|mut v| {
            v.set_sensitive(true);
            v
        });
    (format!("{scheme}://{host}"), value)
}

/// Reads of public buckets go unsigned: no access key, and no role to assume.
fn anonymous() -> bool {
    let set = |k: &str| std::env::var_os(k).is_some_and(|v| !v.is_empty());
    !set("AWS_ACCESS_KEY_ID")
        && !set("AWS_WEB_IDENTITY_TOKEN_FILE")
        && !set("AWS_CONTAINER_CREDENTIALS_RELATIVE_URI")
        && !set("AWS_CONTAINER_CREDENTIALS_FULL_URI")
}

/// [`describe`] as the error of the request for `range` of `object`.
pub fn failure(object: &Object, range: Option<&Range<u64>>, e: &object_store::Error) -> FetchError {
    FetchError::at(&object.url, range, describe(object, range, e))
}

/// What a request for `object` (bytes `range`, where one) failed with, in words (the
/// caller's error names the URL, as it names a file).
pub fn describe(object: &Object, range: Option<&Range<u64>>, e: &object_store::Error) -> String {
    let what = match range {
        Some(r) => format!("bytes {}-{}", r.start, r.end.saturating_sub(1)),
        None => "GET".to_string(),
    };
    use object_store::Error as E;
    match e {
        E::NotFound { .. } => format!("{what}: no such object (HTTP 404)"),
        E::PermissionDenied { .. } | E::Unauthenticated { .. } => {
            if object.s3 {
                let creds = if anonymous() {
                    "no credentials were set, so the request went unsigned (a public bucket's way): set "
                } else {
                    "the credentials set may not read it: check "
                };
                format!("{what}: access denied (HTTP 401/403); {creds}{AWS_VARIABLES}")
            } else {
                format!("{what}: access denied (HTTP 401/403); arbvis sends no credentials over HTTP (an S3 bucket is read as s3://BUCKET/KEY with {AWS_VARIABLES})")
            }
        }
        E::Precondition { .. } => format!(
            "{what}: the object changed while it was read (its ETag is not the one it had when it was opened); open it again"
        ),
        other => {
            let text = other.to_string();
            let chain = causes(other).to_ascii_lowercase();
            if ["tls", "certificate", "handshake", "invalidcontenttype", "corrupt message"]
                .iter()
                .any(|w| chain.contains(w))
            {
                format!("{what}: the TLS connection failed (the server's certificate was refused, or it does not speak TLS on that port: {}); check the URL's scheme and port, or the server's certificate", arbvis_core::input::shorten(&last_cause(other), 160))
            } else if text.contains("error following redirect") || chain.contains("too many redirects") {
                format!("{what}: the server's redirects did not end (a redirect loop, or more than 10 in a row)")
            } else if text.contains("redirect without LOCATION") {
                format!("{what}: the server answered with a redirect (HTTP 301-308) naming no location; from S3 this means the bucket lies in another region: set AWS_REGION to the bucket's region (or AWS_ENDPOINT_URL to the server that holds it)")
            } else if object.s3 && !anonymous() && is_redirect(&text) {
                format!("{what}: the server redirected the request to another host, and a signed request's credentials (the session token) are not sent to another host: set AWS_REGION to the bucket's region or AWS_ENDPOINT_URL to the server that holds it")
            } else if text.contains("error sending request") || text.contains("Connection refused") {
                let retried = text.contains("after ") && text.contains(" retries");
                let tries = if retried { ", tried again with backoff" } else { "" };
                format!("{what}: the server could not be reached (no connection to it{tries}); check the host, the port and the network")
            } else if text.contains("non-partial response") || text.contains("Range request not supported") {
                format!("{what}: the server ignored the Range request (it answered 200 with the whole object); arbvis reads a part of an object only from servers that honour Range")
            } else {
                format!("{what}: {text}")
            }
        }
    }
}

/// `e` and every error below it, joined (the words that tell a TLS failure from a refused
/// connection are in the causes, not in object_store's own message).
fn causes(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// The deepest cause of `e` (what the TLS library or the socket said).
fn last_cause(e: &dyn std::error::Error) -> String {
    let mut last = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        last = s.to_string();
        source = s.source();
    }
    last
}

/// Whether object_store's error text is a redirect it did not follow (HTTP 3xx).
fn is_redirect(text: &str) -> bool {
    ["301", "302", "303", "307", "308"]
        .iter()
        .any(|code| text.contains(&format!("status {code}")) || text.contains(&format!("{code} ")))
        || text.to_ascii_lowercase().contains("redirect")
}
