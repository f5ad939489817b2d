//! OpenAI-compatible chat completions over HTTP, with the server dialects for constrained
//! decoding, bounded retries, and one diagnostic per way a reply can be unusable.

use crate::diag::Diagnostic;
use serde::Serialize;
use serde_json::{Value, json};
use std::path::Path;
use std::time::{Duration, Instant};

/// Reply bodies above this are cut off (E0609): a scenario is a few KiB.
pub const MAX_BODY_BYTES: u64 = 4 << 20;
/// Message content above this is refused (E0609).
pub const MAX_CONTENT_BYTES: usize = 64 << 10;
/// `Retry-After` is honoured up to this long, so a hostile header cannot park the CLI.
const MAX_RETRY_AFTER: Duration = Duration::from_secs(30);

/// An image for a vision model (the `--image` sketch of `rocc text`, the CIREN sketch of `rocc
/// ciren extract`), already encoded as a base64 data URL.
#[derive(Clone, Debug)]
pub struct Image {
    pub data_url: String,
    /// Size of the encoded file, for messages and transcripts.
    pub bytes: usize,
}

/// Images larger than this are refused: servers reject them anyway.
pub const MAX_IMAGE_BYTES: usize = 20 << 20;

impl Image {
    /// An `--image` file (E0614 when unusable).
    pub fn from_file(path: &Path) -> Result<Image, Diagnostic> {
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        let mime = match ext.as_str() {
            "png" => "image/png",
            "jpg" | "jpeg" => "image/jpeg",
            "webp" => "image/webp",
            "gif" => "image/gif",
            _ => {
                return Err(Diagnostic::error(
                    "E0614",
                    format!("--image `{}` is not PNG, JPEG, WebP or GIF", path.display()),
                )
                .help("pass a .png, .jpg, .webp or .gif file"));
            }
        };
        let bytes = std::fs::read(path).map_err(|e| {
            Diagnostic::error("E0614", format!("cannot read --image `{}`: {e}", path.display())).help("check the path")
        })?;
        if bytes.len() > MAX_IMAGE_BYTES {
            return Err(Diagnostic::error("E0614", format!("--image `{}` is {} bytes", path.display(), bytes.len()))
                .help("scale the sketch down below 20 MiB"));
        }
        Ok(Image::from_bytes(&bytes, mime))
    }

    pub fn from_bytes(bytes: &[u8], mime: &str) -> Image {
        Image { data_url: format!("data:{mime};base64,{}", base64(bytes)), bytes: bytes.len() }
    }

    /// The MIME type the file's first bytes announce, if it is an image a vision server takes.
    pub fn sniff(bytes: &[u8]) -> Option<&'static str> {
        if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
            Some("image/jpeg")
        } else if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
            Some("image/png")
        } else if bytes.starts_with(b"GIF87a") || bytes.starts_with(b"GIF89a") {
            Some("image/gif")
        } else if bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
            Some("image/webp")
        } else {
            None
        }
    }
}

/// Standard base64 with padding (RFC 4648): the only encoding data URLs need.
pub fn base64(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n =
            (u32::from(c[0]) << 16) | (u32::from(*c.get(1).unwrap_or(&0)) << 8) | u32::from(*c.get(2).unwrap_or(&0));
        for (i, shift) in [18, 12, 6, 0].into_iter().enumerate() {
            out.push(if i <= c.len() { T[(n >> shift) as usize & 63] as char } else { '=' });
        }
    }
    out
}

/// One chat message. Without images the content is a plain string, which every server takes;
/// with images it is the OpenAI list of parts: the text first, then one `image_url` part per
/// image (vLLM, llama.cpp with a multimodal projector, Ollama and OpenAI all read this form).
pub fn message(role: &str, text: &str, images: &[Image]) -> Value {
    if images.is_empty() {
        return json!({"role": role, "content": text});
    }
    let mut parts = vec![json!({"type": "text", "text": text})];
    parts.extend(images.iter().map(|i| json!({"type": "image_url", "image_url": {"url": i.data_url}})));
    json!({"role": role, "content": parts})
}

/// A copy of a request with every image data URL cut to its header and length: transcripts
/// record what was sent without carrying megabytes of base64.
pub fn redact_images(v: &Value) -> Value {
    match v {
        Value::String(s) if s.starts_with("data:") && s.len() > 200 => {
            let head = s.split_once(',').map_or("data:", |(h, _)| h);
            Value::String(format!("{head},<{} base64 characters>", s.len() - head.len() - 1))
        }
        Value::Array(a) => Value::Array(a.iter().map(redact_images).collect()),
        Value::Object(o) => Value::Object(o.iter().map(|(k, v)| (k.clone(), redact_images(v))).collect()),
        other => other.clone(),
    }
}

/// Which server sits behind the endpoint: decides how constraints are sent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Server {
    /// vLLM: `structured_outputs: {"grammar": ...}` / `{"json": ...}`. (The old `guided_grammar`
    /// field is silently ignored by recent vLLM, so it is never sent.)
    Vllm,
    /// llama.cpp server: `grammar` (GBNF) / `response_format` with a JSON schema.
    Llamacpp,
    /// Ollama's OpenAI-compatible endpoint: no grammar field; JSON schema via `response_format`.
    Ollama,
    /// OpenAI and other hosted APIs: no grammar field; JSON schema via `response_format`.
    Openai,
}

impl Server {
    pub fn name(self) -> &'static str {
        match self {
            Server::Vllm => "vllm",
            Server::Llamacpp => "llamacpp",
            Server::Ollama => "ollama",
            Server::Openai => "openai",
        }
    }
    pub fn supports_grammar(self) -> bool {
        matches!(self, Server::Vllm | Server::Llamacpp)
    }
    /// The usual base URL of a local server of this kind.
    pub fn default_endpoint(self) -> &'static str {
        match self {
            Server::Vllm => "http://127.0.0.1:8000/v1",
            Server::Llamacpp => "http://127.0.0.1:8080/v1",
            Server::Ollama => "http://127.0.0.1:11434/v1",
            Server::Openai => "https://api.openai.com/v1",
        }
    }
}

/// What the server may generate.
#[derive(Clone, Debug, PartialEq)]
pub enum Constraint {
    None,
    /// A GBNF grammar (sent only to servers that take one).
    Grammar(String),
    /// A JSON schema for a JSON object reply.
    Json(Value),
}

#[derive(Clone, Debug)]
pub struct ClientConfig {
    pub endpoint: String,
    pub model: String,
    pub api_key: Option<String>,
    pub server: Server,
    pub timeout: Duration,
    /// Extra attempts after a 429 or 5xx.
    pub retries: u32,
    /// First backoff; doubles each retry.
    pub backoff: Duration,
    pub max_tokens: u32,
    pub temperature: f64,
    /// Sent as the request `seed` so sampling servers repeat themselves.
    pub seed: u64,
}

/// One request and what came of it, for `--transcript`. The API key is never recorded (it
/// travels in a header, not the body).
#[derive(Clone, Debug, Serialize)]
pub struct Exchange {
    pub stage: String,
    pub attempt: u32,
    pub request: Value,
    pub status: Option<u16>,
    pub reply: Option<String>,
    pub error: Option<String>,
    pub elapsed_ms: u64,
}

pub struct Client {
    cfg: ClientConfig,
    url: String,
    agent: ureq::Agent,
}

impl Client {
    pub fn new(cfg: ClientConfig) -> Result<Client, Diagnostic> {
        let base = cfg.endpoint.trim_end_matches('/');
        if !(base.starts_with("http://") || base.starts_with("https://")) {
            return Err(Diagnostic::error("E0614", format!("endpoint `{base}` is not an http:// or https:// URL"))
                .help("pass the server's OpenAI-compatible base URL, e.g. http://127.0.0.1:8080/v1"));
        }
        if base.starts_with("https://") && !cfg!(feature = "https") {
            return Err(Diagnostic::error("E0614", format!("endpoint `{base}` needs TLS, which this build lacks"))
                .help("rebuild with `cargo build --features https`, or reach the server over http on loopback"));
        }
        let url =
            if base.ends_with("/chat/completions") { base.to_string() } else { format!("{base}/chat/completions") };
        let agent: ureq::Agent = ureq::Agent::config_builder()
            .timeout_global(Some(cfg.timeout))
            .timeout_connect(Some(cfg.timeout.min(Duration::from_secs(10))))
            // Statuses are inspected here: retries and error bodies need them.
            .http_status_as_error(false)
            .max_redirects(0)
            .build()
            .into();
        Ok(Client { cfg, url, agent })
    }

    pub fn config(&self) -> &ClientConfig {
        &self.cfg
    }

    /// Change the reply budget (the goal stage needs far fewer tokens than a whole file).
    pub fn set_max_tokens(&mut self, n: u32) {
        self.cfg.max_tokens = n;
    }

    /// Change the sampling temperature (the CIREN conflict call is always greedy).
    pub fn set_temperature(&mut self, t: f64) {
        self.cfg.temperature = t;
    }

    /// The request body in this server's dialect.
    pub fn body(&self, messages: &[Value], constraint: &Constraint) -> Value {
        let c = &self.cfg;
        let mut body = json!({
            "model": c.model,
            "messages": messages,
            "max_tokens": c.max_tokens,
            "temperature": c.temperature,
            "seed": c.seed,
            "stream": false,
        });
        match (constraint, c.server) {
            (Constraint::None, _) => {}
            (Constraint::Grammar(g), Server::Vllm) => body["structured_outputs"] = json!({ "grammar": g }),
            (Constraint::Grammar(g), Server::Llamacpp) => body["grammar"] = json!(g),
            // Ollama and OpenAI have no grammar field: the checker and the repair loop carry it.
            (Constraint::Grammar(_), Server::Ollama | Server::Openai) => {}
            (Constraint::Json(s), Server::Vllm) => body["structured_outputs"] = json!({ "json": s }),
            (Constraint::Json(s), _) => {
                body["response_format"] =
                    json!({"type": "json_schema", "json_schema": {"name": "rocc_schema", "schema": s}});
            }
        }
        body
    }

    /// One chat completion: the assistant's text, or the diagnostic saying why there is none.
    pub fn chat(
        &self,
        stage: &str,
        messages: &[Value],
        constraint: &Constraint,
        log: &mut Vec<Exchange>,
    ) -> Result<String, Diagnostic> {
        let body = self.body(messages, constraint);
        let bytes = serde_json::to_vec(&body).expect("a JSON value serialises");
        let mut attempt = 0;
        loop {
            let started = Instant::now();
            let mut ex = Exchange {
                stage: stage.to_string(),
                attempt,
                request: body.clone(),
                status: None,
                reply: None,
                error: None,
                elapsed_ms: 0,
            };
            let result = self.send(&bytes, &mut ex);
            ex.elapsed_ms = started.elapsed().as_millis() as u64;
            if let Err(Retry::After(_, d) | Retry::Never(d)) = &result {
                ex.error = Some(d.to_string());
            }
            log.push(ex);
            match result {
                Ok(text) => return Ok(text),
                Err(Retry::After(wait, d)) if attempt < self.cfg.retries => {
                    let backoff = self.cfg.backoff.saturating_mul(1 << attempt.min(16));
                    std::thread::sleep(wait.map_or(backoff, |w| w.min(MAX_RETRY_AFTER)));
                    attempt += 1;
                    let _ = d; // superseded by the next attempt's outcome
                }
                Err(Retry::After(_, d)) => {
                    let tries = attempt + 1;
                    let d = if tries > 1 {
                        Diagnostic { message: format!("{} (after {tries} attempts)", d.message), ..d }
                    } else {
                        d
                    };
                    return Err(d);
                }
                Err(Retry::Never(d)) => return Err(d),
            }
        }
    }

    fn send(&self, bytes: &[u8], ex: &mut Exchange) -> Result<String, Retry> {
        let mut req = self.agent.post(&self.url).header("Content-Type", "application/json");
        if let Some(k) = &self.cfg.api_key {
            req = req.header("Authorization", format!("Bearer {k}"));
        }
        let resp = req.send(bytes).map_err(|e| Retry::Never(self.transport_error(e)))?;
        let status = resp.status().as_u16();
        ex.status = Some(status);
        let retry_after = resp
            .headers()
            .get("retry-after")
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.trim().parse::<u64>().ok())
            .map(Duration::from_secs);
        let raw = resp
            .into_body()
            .with_config()
            .limit(MAX_BODY_BYTES)
            .read_to_vec()
            .map_err(|e| Retry::Never(self.transport_error(e)))?;
        let text = String::from_utf8(raw).map_err(|e| {
            Retry::Never(
                Diagnostic::error("E0608", format!("the reply from {} is not UTF-8 ({e})", self.url))
                    .help("the server or a proxy is misconfigured; `rocc explain E0608`"),
            )
        })?;
        ex.reply = Some(text.clone());
        if !(200..300).contains(&status) {
            let d = http_error(status, &text, &self.url);
            return Err(if status == 429 || status >= 500 { Retry::After(retry_after, d) } else { Retry::Never(d) });
        }
        parse_reply(&text).map_err(Retry::Never)
    }

    fn transport_error(&self, e: ureq::Error) -> Diagnostic {
        let url = &self.url;
        match e {
            ureq::Error::Timeout(t) => {
                Diagnostic::error("E0602", format!("no reply from {url} within {:?} ({t})", self.cfg.timeout))
                    .help("raise --timeout or lower --max-tokens; `rocc explain E0602`")
            }
            ureq::Error::BodyExceedsLimit(n) => {
                Diagnostic::error("E0609", format!("the reply from {url} is over {n} bytes"))
                    .help("lower --max-tokens; `rocc explain E0609`")
            }
            ureq::Error::HostNotFound => Diagnostic::error("E0601", format!("cannot resolve the host of {url}"))
                .help("check --endpoint (or ROCC_LLM_ENDPOINT)"),
            ureq::Error::Io(io) if io.kind() == std::io::ErrorKind::TimedOut => {
                Diagnostic::error("E0602", format!("no reply from {url} within {:?}", self.cfg.timeout))
                    .help("raise --timeout or lower --max-tokens; `rocc explain E0602`")
            }
            ureq::Error::Io(io) => Diagnostic::error("E0601", format!("cannot reach {url}: {io}"))
                .help(format!("is the {} server running? docs/llm.md has the commands", self.cfg.server.name())),
            ureq::Error::ConnectionFailed => Diagnostic::error("E0601", format!("cannot connect to {url}"))
                .help(format!("is the {} server running? docs/llm.md has the commands", self.cfg.server.name())),
            e => Diagnostic::error("E0601", format!("request to {url} failed: {e}"))
                .help("check --endpoint; `rocc explain E0601`"),
        }
    }
}

enum Retry {
    /// 429 / 5xx: worth another try, after the server's `Retry-After` if it gave one.
    After(Option<Duration>, Diagnostic),
    Never(Diagnostic),
}

/// At most `n` characters of `s`, on one line, for messages.
pub fn excerpt(s: &str, n: usize) -> String {
    let one: String = s.chars().map(|c| if c.is_control() { ' ' } else { c }).take(n).collect();
    if s.chars().count() > n { format!("{one}...") } else { one }
}

fn http_error(status: u16, body: &str, url: &str) -> Diagnostic {
    // OpenAI-style `{"error": {"message": ...}}` or a plain string: show the server's words.
    let said = serde_json::from_str::<Value>(body)
        .ok()
        .and_then(|v| {
            let e = v.get("error")?;
            Some(e.get("message").and_then(Value::as_str).map(str::to_string).unwrap_or_else(|| e.to_string()))
        })
        .unwrap_or_else(|| body.to_string());
    let lower = said.to_ascii_lowercase();
    let help = match status {
        // llama.cpp without a projector: "image input is not supported - hint: ... mmproj".
        _ if lower.contains("image") && (lower.contains("not supported") || lower.contains("mmproj")) => {
            "the model behind this endpoint takes no images: serve a vision model (vLLM with a -VL model, llama-server with --mmproj)".to_string()
        }
        401 | 403 => "pass --api-key or set ROCC_LLM_API_KEY".to_string(),
        404 => "the endpoint should end in /v1 and --model must name a model the server has".to_string(),
        400 => {
            "the server rejected the request; if it mentions the grammar, pick the right --server or pass --no-grammar"
                .to_string()
        }
        429 => "the server is rate-limiting; retry later or raise --retries".to_string(),
        _ => "`rocc explain E0603`".to_string(),
    };
    Diagnostic::error("E0603", format!("{url} answered HTTP {status}: {}", excerpt(&said, 300))).help(help)
}

/// The assistant text of a chat-completion body, or why it has none.
pub fn parse_reply(body: &str) -> Result<String, Diagnostic> {
    let v: Value = serde_json::from_str(body).map_err(|e| {
        Diagnostic::error("E0604", format!("the reply is not JSON ({e}): `{}`", excerpt(body, 120)))
            .help("is --endpoint an OpenAI-compatible /v1 base URL? `rocc explain E0604`")
    })?;
    if let Some(e) = v.get("error").filter(|e| !e.is_null()) {
        let msg = e.get("message").and_then(Value::as_str).map(str::to_string).unwrap_or_else(|| e.to_string());
        return Err(Diagnostic::error("E0603", format!("the server reported an error: {}", excerpt(&msg, 300)))
            .help("`rocc explain E0603`"));
    }
    let Some(choices) = v.get("choices") else {
        return Err(Diagnostic::error("E0604", format!("the reply has no `choices`: `{}`", excerpt(body, 120)))
            .help("is --endpoint an OpenAI-compatible /v1 base URL? `rocc explain E0604`"));
    };
    let Some(choice) = choices.as_array().and_then(|a| a.first()) else {
        return Err(Diagnostic::error("E0605", "the reply has no choices")
            .help("the prompt may exceed the model's context; `rocc explain E0605`"));
    };
    let message = choice.get("message").ok_or_else(|| {
        Diagnostic::error("E0604", "the reply's choice has no `message`").help("`rocc explain E0604`")
    })?;
    let finish = choice.get("finish_reason").and_then(Value::as_str).unwrap_or("");
    if let Some(r) = message.get("refusal").and_then(Value::as_str).filter(|r| !r.trim().is_empty()) {
        return Err(Diagnostic::error("E0607", format!("the model refused: {}", excerpt(r, 300)))
            .help("rephrase the sentence; `rocc explain E0607`"));
    }
    if finish == "content_filter" {
        return Err(Diagnostic::error("E0607", "the reply was withheld by the server's content filter")
            .help("rephrase the sentence; `rocc explain E0607`"));
    }
    let content = match message.get("content") {
        Some(Value::String(s)) => s.clone(),
        // Some servers send content as a list of parts.
        Some(Value::Array(parts)) => {
            parts.iter().filter_map(|p| p.get("text").and_then(Value::as_str)).collect::<Vec<_>>().join("")
        }
        Some(Value::Null) | None => String::new(),
        Some(other) => {
            return Err(Diagnostic::error(
                "E0604",
                format!("message content is not text: {}", excerpt(&other.to_string(), 120)),
            )
            .help("`rocc explain E0604`"));
        }
    };
    if content.len() > MAX_CONTENT_BYTES {
        return Err(Diagnostic::error("E0609", format!("the reply is {} bytes of text", content.len()))
            .help("lower --max-tokens; `rocc explain E0609`"));
    }
    if finish == "length" {
        return Err(Diagnostic::error(
            "E0606",
            format!("the reply was cut off at --max-tokens: `...{}`", excerpt(tail(&content, 80), 80)),
        )
        .help("raise --max-tokens; `rocc explain E0606`"));
    }
    if content.trim().is_empty() {
        return Err(Diagnostic::error("E0605", "the model's reply is empty")
            .help("the prompt may exceed the model's context; `rocc explain E0605`"));
    }
    Ok(content)
}

fn tail(s: &str, n: usize) -> &str {
    let count = s.chars().count();
    match s.char_indices().nth(count.saturating_sub(n)) {
        Some((i, _)) => &s[i..],
        None => s,
    }
}
