//! The HTTP clients object_store is given where its own will not do: signed S3 requests
//! that must not follow a redirect to another host, and an object whose URL carries a
//! query (a pre-signed URL's signature, a token) that every request must repeat.

use std::future::Future;
use std::pin::Pin;
use std::time::Duration;

use object_store::client::{
    HttpClient, HttpConnector, HttpError, HttpErrorKind, HttpRequest, HttpResponse, HttpService,
};
use object_store::ClientOptions;

/// A reqwest client with object_store's settings as arbvis sets them (the request
/// timeout `t`, the pool, no transparent decompression: `Content-Length` must be the
/// object's), and `redirect` as its redirect policy.
fn reqwest_client(
    t: Duration,
    redirect: reqwest::redirect::Policy,
) -> object_store::Result<reqwest::Client> {
    reqwest::Client::builder()
        .user_agent(concat!("arbvis/", env!("CARGO_PKG_VERSION")))
        .timeout(t)
        .connect_timeout(t.min(Duration::from_secs(10)))
        .pool_max_idle_per_host(64)
        .no_gzip()
        .no_brotli()
        .no_zstd()
        .no_deflate()
        .redirect(redirect)
        .build()
        .map_err(|e| object_store::Error::Generic {
            store: "HTTP",
            source: Box::new(e),
        })
}

/// The HTTP client of signed S3 requests: a redirect to another origin (scheme, host,
/// port) is not followed. reqwest drops `Authorization` on such a redirect but not
/// `x-amz-security-token`, so following it would send a session token to a host it was
/// not meant for; the redirect is an error that says so instead.
/// Its field: the request timeout.
#[derive(Debug)]
pub struct SameHostRedirects(pub Duration);

impl HttpConnector for SameHostRedirects {
    fn connect(&self, _: &ClientOptions) -> object_store::Result<HttpClient> {
        use reqwest::redirect::{Attempt, Policy};
        let policy = Policy::custom(|attempt: Attempt<'_>| {
            let first = &attempt.previous()[0];
            if attempt.previous().len() > 10 {
                attempt.error("more than 10 redirects")
            } else if attempt.url().origin() == first.origin() {
                attempt.follow()
            } else {
                attempt.stop()
            }
        });
        Ok(HttpClient::new(reqwest_client(self.0, policy)?))
    }
}

/// The HTTP client of one object whose URL has a query: the query (`X-Amz-Signature=...`,
/// `token=...`) added to every request's URL, as the server that signed it expects.
/// Its fields: the query, and the request timeout.
#[derive(Debug)]
pub struct WithQuery(pub String, pub Duration);

impl HttpConnector for WithQuery {
    fn connect(&self, _: &ClientOptions) -> object_store::Result<HttpClient> {
        let client = reqwest_client(self.1, reqwest::redirect::Policy::limited(10))?;
        Ok(HttpClient::new(QueryService {
            client,
            query: self.0.clone(),
        }))
    }
}

/// [`WithQuery`]'s service: reqwest with the query appended.
#[derive(Debug)]
struct QueryService {
    client: reqwest::Client,
    query: String,
}

/// What [`HttpService::call`] returns (the trait is `async_trait`'s, written out).
type Answer<'a> = Pin<Box<dyn Future<Output = Result<HttpResponse, HttpError>> + Send + 'a>>;

impl HttpService for QueryService {
    fn call<'life0, 'async_trait>(&'life0 self, mut req: HttpRequest) -> Answer<'async_trait>
    where
        'life0: 'async_trait,
        Self: 'async_trait,
    {
        let uri = req.uri().to_string();
        let joined = if uri.contains('?') { '&' } else { '?' };
        match format!("{uri}{joined}{}", self.query).parse() {
            Ok(with_query) => *req.uri_mut() = with_query,
            Err(e) => {
                return Box::pin(async move { Err(HttpError::new(HttpErrorKind::Request, e)) })
            }
        }
        HttpService::call(&self.client, req)
    }
}
