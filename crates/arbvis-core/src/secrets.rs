//! Secrets a URL may carry (a password in its user info, a pre-signed or tokened query's
//! signature, credential or token) kept out of everything arbvis prints or writes: error
//! lines, `inspect`, the disk cache's entry headers, the scene text a PNG embeds. The
//! request to the URL's own host is the only place they go.

/// Query parameters whose values are secrets (compared without regard to case): AWS
/// SigV4 and Google Cloud Storage pre-signed URLs, Azure SAS signatures, bearer tokens.
const SECRET_PARAMETERS: &[&str] = &[
    "x-amz-signature",
    "x-amz-credential",
    "x-amz-security-token",
    "x-goog-signature",
    "x-goog-credential",
    "signature",
    "sig",
    "token",
    "access_token",
    "password",
];

/// What a secret is replaced with.
pub const HIDDEN: &str = "***";

/// `text` with the password of every URL in it (`scheme://user:PASSWORD@host`) and the
/// values of its secret query parameters ([`SECRET_PARAMETERS`]) replaced by
/// [`HIDDEN`]; everything else as it was. A URL ends at white space, a quote or `<>`.
pub fn redact(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find("://") {
        let start = at + 3;
        out.push_str(&rest[..start]);
        let end = rest[start..]
            .find(|c: char| c.is_whitespace() || matches!(c, '"' | '\'' | '<' | '>' | '`'))
            .map_or(rest.len(), |e| start + e);
        out.push_str(&redact_url_tail(&rest[start..end]));
        rest = &rest[end..];
    }
    out.push_str(rest);
    out
}

/// Whether `text` holds a secret [`redact`] would hide.
pub fn has_secret(text: &str) -> bool {
    redact(text) != text
}

/// A URL after its `scheme://`: the password and secret query values hidden.
fn redact_url_tail(tail: &str) -> String {
    let authority_end = tail.find(['/', '?', '#']).unwrap_or(tail.len());
    let (authority, path) = tail.split_at(authority_end);
    let mut out = String::with_capacity(tail.len());
    match authority.rsplit_once('@') {
        Some((user_info, host)) => {
            match user_info.split_once(':') {
                Some((user, _password)) => {
                    out.push_str(user);
                    out.push(':');
                    out.push_str(HIDDEN);
                }
                None => out.push_str(user_info),
            }
            out.push('@');
            out.push_str(host);
        }
        None => out.push_str(authority),
    }
    let (before_query, query) = match path.split_once('?') {
        Some((p, q)) => (p, Some(q)),
        None => (path, None),
    };
    out.push_str(before_query);
    if let Some(query) = query {
        let (query, fragment) = match query.split_once('#') {
            Some((q, f)) => (q, Some(f)),
            None => (query, None),
        };
        out.push('?');
        let pairs: Vec<String> = query.split('&').map(redact_parameter).collect();
        out.push_str(&pairs.join("&"));
        if let Some(f) = fragment {
            out.push('#');
            out.push_str(f);
        }
    }
    out
}

/// One `name=value` of a query, its value hidden where the name is a secret's.
fn redact_parameter(pair: &str) -> String {
    match pair.split_once('=') {
        Some((name, value))
            if !value.is_empty()
                && SECRET_PARAMETERS
                    .iter()
                    .any(|s| s.eq_ignore_ascii_case(name)) =>
        {
            format!("{name}={HIDDEN}")
        }
        _ => pair.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passwords_and_secret_parameters_are_hidden_and_the_rest_kept() {
        let cases = [
            (
                "http://alice:s3cr%40t@host:8080/a/b.zarr/zarr.json: refused",
                "http://alice:***@host:8080/a/b.zarr/zarr.json: refused",
            ),
            // A password with ':' and '@' in it (the last '@' ends the user info).
            ("https://u:p:a@ss@h/x", "https://u:***@h/x"),
            // A user without a password keeps its name; no URL at all is unchanged.
            ("s3://key@bucket/k", "s3://key@bucket/k"),
            ("no url here: a:b@c", "no url here: a:b@c"),
            (
                "GET \"https://h/k.laz?X-Amz-Credential=AK%2F1&X-Amz-Date=1&X-Amz-Signature=ab12&x-amz-security-token=T\" failed",
                "GET \"https://h/k.laz?X-Amz-Credential=***&X-Amz-Date=1&X-Amz-Signature=***&x-amz-security-token=***\" failed",
            ),
            (
                "https://h/k?token=abc#frag and http://a:b@c",
                "https://h/k?token=***#frag and http://a:***@c",
            ),
            // Scene text: a quoted URL inside TOML.
            (
                "volume = { store = \"http://me:pw@10.0.0.1/s.zarr\" }",
                "volume = { store = \"http://me:***@10.0.0.1/s.zarr\" }",
            ),
        ];
        for (text, want) in cases {
            assert_eq!(redact(text), want, "{text}");
            assert!(has_secret(text) == (text != want), "{text}");
            // Hiding twice hides nothing more.
            assert_eq!(redact(want), want);
        }
    }
}
