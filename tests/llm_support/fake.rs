//! An in-process fake OpenAI-compatible server with scripted replies, shared by the tests of
//! every model route (`tests/llm.rs`: `rocc text`; `tests/ciren_extract.rs`: `rocc ciren
//! extract`). It records each request's JSON body and head, so a test can assert what was sent.
#![allow(dead_code)] // each test crate uses part of it

use serde_json::{Value, json};
use std::io::{Read, Write};
use std::net::TcpListener;
use std::sync::{Arc, Mutex};
use std::time::Duration;

pub enum Reply {
    /// Status, body bytes, extra headers.
    Http(u16, Vec<u8>, Vec<(&'static str, &'static str)>),
    /// Read the request, then say nothing for this long.
    Hang(Duration),
}

pub fn ok(body: Value) -> Reply {
    Reply::Http(200, body.to_string().into_bytes(), vec![])
}

/// A chat completion whose assistant message is `content`.
pub fn chat(content: &str) -> Reply {
    ok(json!({"id": "x", "object": "chat.completion",
        "choices": [{"index": 0, "finish_reason": "stop", "message": {"role": "assistant", "content": content}}]}))
}

pub struct Fake {
    pub url: String,
    requests: Arc<Mutex<Vec<Value>>>,
    heads: Arc<Mutex<Vec<String>>>,
}

impl Fake {
    /// The JSON bodies received, in order (`null` for a body that is not JSON).
    pub fn requests(&self) -> Vec<Value> {
        self.requests.lock().unwrap().clone()
    }
    /// The request lines and headers received, lower-cased, in order.
    pub fn heads(&self) -> Vec<String> {
        self.heads.lock().unwrap().clone()
    }
}

/// The text parts of a message's content, joined (plain-string content as is).
pub fn text_of(message: &Value) -> String {
    match &message["content"] {
        Value::String(s) => s.clone(),
        Value::Array(parts) => parts.iter().filter_map(|p| p["text"].as_str()).collect::<Vec<_>>().join("\n"),
        _ => String::new(),
    }
}

/// The `image_url` URLs of a message's content.
pub fn images_of(message: &Value) -> Vec<String> {
    match &message["content"] {
        Value::Array(parts) => parts
            .iter()
            .filter(|p| p["type"] == "image_url")
            .filter_map(|p| p["image_url"]["url"].as_str().map(str::to_string))
            .collect(),
        _ => vec![],
    }
}

/// A one-thread HTTP/1.1 server on 127.0.0.1:0 that answers each connection with the next
/// scripted reply (and records the requests). After the script it stops accepting, so a
/// request beyond it fails to connect (E0601), which tests can assert.
pub fn serve(replies: Vec<Reply>) -> Fake {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let url = format!("http://{}/v1", listener.local_addr().unwrap());
    let requests = Arc::new(Mutex::new(vec![]));
    let heads = Arc::new(Mutex::new(vec![]));
    let (log, head_log) = (requests.clone(), heads.clone());
    std::thread::spawn(move || {
        for reply in replies {
            let Ok((mut s, _)) = listener.accept() else { return };
            let mut buf = vec![];
            let mut chunk = [0u8; 4096];
            let body_start = loop {
                let n = s.read(&mut chunk).unwrap_or(0);
                if n == 0 {
                    break None;
                }
                buf.extend_from_slice(&chunk[..n]);
                if let Some(p) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
                    break Some(p + 4);
                }
            };
            let Some(start) = body_start else { continue };
            let head = String::from_utf8_lossy(&buf[..start]).to_ascii_lowercase();
            let len: usize = head
                .lines()
                .find_map(|l| l.strip_prefix("content-length:").map(|v| v.trim().parse().unwrap()))
                .unwrap_or(0);
            while buf.len() < start + len {
                let n = s.read(&mut chunk).unwrap_or(0);
                if n == 0 {
                    break;
                }
                buf.extend_from_slice(&chunk[..n]);
            }
            head_log.lock().unwrap().push(head);
            log.lock().unwrap().push(serde_json::from_slice(&buf[start..]).unwrap_or(Value::Null));
            match reply {
                Reply::Hang(d) => std::thread::sleep(d),
                Reply::Http(status, body, headers) => {
                    let mut head = format!(
                        "HTTP/1.1 {status} X\r\ncontent-type: application/json\r\ncontent-length: {}\r\nconnection: close\r\n",
                        body.len()
                    );
                    for (k, v) in headers {
                        head.push_str(&format!("{k}: {v}\r\n"));
                    }
                    head.push_str("\r\n");
                    let _ = s.write_all(head.as_bytes());
                    let _ = s.write_all(&body);
                }
            }
        }
    });
    Fake { url, requests, heads }
}
