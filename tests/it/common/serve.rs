//! Loopback servers a test starts and stops: the tests' own HTTP server with `Range` and
//! injected faults (`tests/servers/range_server.py`) and moto's S3 server
//! (`tests/servers/s3_server.py`). Each binds 127.0.0.1 on a free port, says the port on
//! its stdout, and is stopped by its PID when the test drops it (and, should the test die
//! first, by its stdin closing).

use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};

/// A running server.
pub struct Server {
    child: Child,
    /// Its port on 127.0.0.1.
    pub port: u16,
}

fn script(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/servers")
        .join(name)
}

impl Server {
    fn start(args: &[&std::ffi::OsStr]) -> Server {
        let mut child = Command::new("python3")
            .args(args)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("python3 starts");
        let mut line = String::new();
        BufReader::new(child.stdout.take().expect("its stdout"))
            .read_line(&mut line)
            .expect("the server's port");
        let port = match line.trim().parse() {
            Ok(p) => p,
            Err(_) => {
                let _ = child.kill();
                panic!("{args:?} did not start (said {line:?})");
            }
        };
        Server { child, port }
    }

    /// The tests' HTTP server on `folder`.
    pub fn http(folder: &Path) -> Server {
        Server::start(&[script("range_server.py").as_os_str(), folder.as_os_str()])
    }

    /// The tests' server on `folder` over HTTPS with a self-signed certificate
    /// (`tests/servers/self-signed.pem`, for 127.0.0.1), which no client trusts.
    pub fn https_self_signed(folder: &Path) -> Server {
        Server::start(&[
            script("range_server.py").as_os_str(),
            folder.as_os_str(),
            script("self-signed.pem").as_os_str(),
        ])
    }

    /// moto's S3 server with `bucket` holding `folder`'s files, if moto is installed
    /// (else `None` and the test is skipped, or fails under `ARBVIS_NO_SKIP=1`).
    pub fn s3(bucket: &str, folder: &Path) -> Option<Server> {
        if !super::python_has(
            "import moto.server, boto3",
            "moto is not installed (pip install \"moto[server]\")",
        ) {
            return None;
        }
        Some(Server::start(&[
            script("s3_server.py").as_os_str(),
            std::ffi::OsStr::new(bucket),
            folder.as_os_str(),
        ]))
    }

    /// `http://127.0.0.1:PORT/` + `path`.
    pub fn url(&self, path: &str) -> String {
        format!("http://127.0.0.1:{}/{path}", self.port)
    }

    /// GET `path` of the HTTP server's control (`_fault?...`, `_stats`, `_reset`): the body.
    pub fn control(&self, path: &str) -> String {
        let mut s = std::net::TcpStream::connect(("127.0.0.1", self.port)).unwrap();
        write!(
            s,
            "GET /{path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"
        )
        .unwrap();
        let mut text = String::new();
        s.read_to_string(&mut text).unwrap();
        text.split("\r\n\r\n").nth(1).unwrap_or("").to_string()
    }

    /// The HTTP server's counts since its start or the last `_reset`: (requests, bytes).
    pub fn counts(&self) -> (u64, u64) {
        let v: serde_json::Value = serde_json::from_str(&self.control("_stats")).unwrap();
        (
            v["requests"].as_u64().unwrap(),
            v["bytes"].as_u64().unwrap(),
        )
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        drop(self.child.stdin.take());
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
