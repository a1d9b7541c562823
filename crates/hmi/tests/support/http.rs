//! A plain HTTP/1.1 client for the HMI's API tests: one request on a fresh loopback
//! connection, the reply's status, headers (names in lower case) and body (chunked
//! bodies joined), and [`Client`], a logged-in user of the API (its session cookie and
//! CSRF token). Included by `#[path]` in the API and page tests.
#![allow(dead_code)]

use std::net::SocketAddr;
use std::time::Duration;

use serde_json::{json, Value};
use tokio::io::{AsyncReadExt as _, AsyncWriteExt as _};

/// An HTTP reply.
pub(crate) struct Reply {
    pub(crate) status: u16,
    pub(crate) headers: Vec<(String, String)>,
    pub(crate) body: String,
}

impl Reply {
    /// The body as JSON (the test fails with the body when it is not).
    pub(crate) fn json(&self) -> Value {
        serde_json::from_str(&self.body).unwrap_or_else(|e| panic!("{e}: {}", self.body))
    }

    /// A header's value by its lower-case name.
    pub(crate) fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_str())
    }
}

/// One HTTP/1.1 request on a fresh connection (a JSON body with POST or when given).
pub(crate) async fn request(
    address: SocketAddr,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &str,
) -> Reply {
    let mut stream = tokio::net::TcpStream::connect(address).await.unwrap();
    let mut request =
        format!("{method} {path} HTTP/1.1\r\nHost: {address}\r\nConnection: close\r\n");
    for (name, value) in headers {
        request.push_str(&format!("{name}: {value}\r\n"));
    }
    if !body.is_empty() || method == "POST" {
        request.push_str(&format!(
            "Content-Type: application/json\r\nContent-Length: {}\r\n",
            body.len()
        ));
    }
    request.push_str("\r\n");
    request.push_str(body);
    stream.write_all(request.as_bytes()).await.unwrap();
    let mut raw = Vec::new();
    tokio::time::timeout(Duration::from_secs(20), stream.read_to_end(&mut raw))
        .await
        .unwrap()
        .unwrap();
    let text = String::from_utf8_lossy(&raw).into_owned();
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    let mut lines = head.lines();
    let status = lines
        .next()
        .unwrap()
        .split(' ')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    let headers: Vec<(String, String)> = lines
        .filter_map(|l| l.split_once(':'))
        .map(|(n, v)| (n.trim().to_ascii_lowercase(), v.trim().to_owned()))
        .collect();
    // Chunked bodies (the CSV export): join the chunks.
    let body = if headers
        .iter()
        .any(|(n, v)| n == "transfer-encoding" && v.contains("chunked"))
    {
        let mut out = String::new();
        let mut rest = body;
        while let Some((size, after)) = rest.split_once("\r\n") {
            let size = usize::from_str_radix(size.trim(), 16).unwrap();
            if size == 0 {
                break;
            }
            out.push_str(&after[..size]);
            rest = &after[size + 2..];
        }
        out
    } else {
        body.to_owned()
    };
    Reply {
        status,
        headers,
        body,
    }
}

/// The reply to `POST /api/login` as `user`.
pub(crate) async fn login_reply(address: SocketAddr, user: &str, password: &str) -> Reply {
    request(
        address,
        "POST",
        "/api/login",
        &[],
        &json!({"username": user, "password": password}).to_string(),
    )
    .await
}

/// A logged-in user of the HMI's API: its session cookie and its CSRF token, sent with
/// every request that changes something.
pub(crate) struct Client {
    pub(crate) address: SocketAddr,
    pub(crate) cookie: String,
    pub(crate) csrf: String,
}

impl Client {
    /// Logs in (the test fails unless the HMI answers 200 with a strict, HTTP-only cookie).
    pub(crate) async fn login(address: SocketAddr, user: &str, password: &str) -> Client {
        let reply = login_reply(address, user, password).await;
        assert_eq!(reply.status, 200, "{}", reply.body);
        let set_cookie = reply.header("set-cookie").unwrap().to_owned();
        assert!(set_cookie.contains("HttpOnly") && set_cookie.contains("SameSite=Strict"));
        Client {
            address,
            cookie: set_cookie.split(';').next().unwrap().to_owned(),
            csrf: reply.json()["csrf"].as_str().unwrap().to_owned(),
        }
    }

    /// `GET path` in the session.
    pub(crate) async fn get(&self, path: &str) -> Reply {
        request(self.address, "GET", path, &[("Cookie", &self.cookie)], "").await
    }

    /// `method path` with a JSON body, the session and its CSRF token.
    pub(crate) async fn send(&self, method: &str, path: &str, body: Value) -> Reply {
        request(
            self.address,
            method,
            path,
            &[("Cookie", &self.cookie), ("X-CSRF-Token", &self.csrf)],
            &body.to_string(),
        )
        .await
    }

    /// `POST path` with a JSON body, the session and its CSRF token.
    pub(crate) async fn post(&self, path: &str, body: Value) -> Reply {
        self.send("POST", path, body).await
    }
}
