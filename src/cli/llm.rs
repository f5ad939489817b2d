//! What `rocc text` and `rocc ciren extract` share: the server options, and where a run's result
//! goes (OUT once it checks, else OUT.rejected.scn; OUT.transcript.json on request).

use super::{Failure, show, write_file};
use clap::ValueEnum;
use rocc::diag::Diagnostic;
use rocc::llm::client::{ClientConfig, Server};
use rocc::source::SourceMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The options of an LLM command. Help lists them by `display_order`, in steps of ten, so that a
/// command's own options slot in between (`rocc text --plan` after `--server`).
#[derive(clap::Args)]
pub struct LlmArgs {
    /// The server's OpenAI-compatible base URL [env: ROCC_LLM_ENDPOINT; default: the server's usual port on 127.0.0.1].
    #[arg(long, display_order = 10)]
    endpoint: Option<String>,
    /// Model name as the server knows it [env: ROCC_LLM_MODEL]; llama.cpp ignores it.
    #[arg(long, display_order = 11)]
    model: Option<String>,
    /// Bearer token [env: ROCC_LLM_API_KEY, then OPENAI_API_KEY].
    #[arg(long, display_order = 12)]
    api_key: Option<String>,
    /// Server dialect: how grammar constraints are sent (ollama and openai take none).
    #[arg(long, value_enum, default_value = "vllm", display_order = 13)]
    server: ServerArg,
    /// Rounds of sending diagnostics back for a corrected file (and corrections per stage).
    #[arg(long, default_value_t = 3, display_order = 20)]
    pub max_repairs: u32,
    /// Scenario seed (default: a hash of the sentence); also sent as the sampling seed.
    #[arg(long, display_order = 30)]
    pub seed: Option<u64>,
    /// Seconds to wait for one reply.
    #[arg(long, default_value_t = 120.0, display_order = 40)]
    timeout: f64,
    /// Retries after HTTP 429 or 5xx, with exponential backoff from 1 s.
    #[arg(long, default_value_t = 2, display_order = 41)]
    retries: u32,
    #[arg(long, default_value_t = 2048, display_order = 42)]
    max_tokens: u32,
    /// Sampling temperature; 0 (greedy) makes runs repeatable.
    #[arg(long, default_value_t = 0.0, display_order = 43)]
    temperature: f64,
    /// Do not send grammar or JSON-schema constraints.
    #[arg(long, display_order = 50)]
    no_grammar: bool,
    /// Save every request and reply as OUT.transcript.json (the API key is never written).
    #[arg(long, display_order = 51)]
    pub transcript: bool,
}

#[derive(Clone, Copy, ValueEnum)]
enum ServerArg {
    Vllm,
    Llamacpp,
    Ollama,
    Openai,
}

/// An E0614: an LLM option out of range.
pub fn bad_option(message: String, help: &str) -> Diagnostic {
    Diagnostic::error("E0614", message).help(help.to_string())
}

impl LlmArgs {
    /// Send grammar or JSON-schema constraints where the server takes them.
    pub fn constrain(&self) -> bool {
        !self.no_grammar
    }

    /// The client: each of endpoint, model and API key from its flag, else its environment
    /// variable, else (the endpoint) the dialect's usual local port; `--timeout` and `--model`
    /// checked (E0614).
    pub fn client(&self) -> Result<ClientConfig, Diagnostic> {
        let server = match self.server {
            ServerArg::Vllm => Server::Vllm,
            ServerArg::Llamacpp => Server::Llamacpp,
            ServerArg::Ollama => Server::Ollama,
            ServerArg::Openai => Server::Openai,
        };
        let env = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
        let endpoint = self
            .endpoint
            .clone()
            .or_else(|| env("ROCC_LLM_ENDPOINT"))
            .unwrap_or_else(|| server.default_endpoint().into());
        let api_key = self.api_key.clone().or_else(|| env("ROCC_LLM_API_KEY")).or_else(|| env("OPENAI_API_KEY"));
        if !(self.timeout.is_finite() && self.timeout > 0.0) {
            let m = format!("--timeout {} is not a positive number of seconds", self.timeout);
            return Err(bad_option(m, "e.g. --timeout 120"));
        }
        let model = match (self.model.clone().or_else(|| env("ROCC_LLM_MODEL")), server) {
            (Some(m), _) => m,
            // llama.cpp serves the one model it loaded and ignores the field.
            (None, Server::Llamacpp) => "default".to_string(),
            (None, s) => {
                return Err(bad_option(
                    format!("--model is required with --server {}", s.name()),
                    "pass the model name the server lists at /v1/models, or set ROCC_LLM_MODEL",
                ));
            }
        };
        Ok(ClientConfig {
            endpoint,
            model,
            api_key,
            server,
            timeout: Duration::from_secs_f64(self.timeout),
            retries: self.retries,
            backoff: Duration::from_secs(1),
            max_tokens: self.max_tokens,
            temperature: self.temperature,
            seed: self.seed.unwrap_or(0),
        })
    }
}

/// Where a run's result goes. The `-o` file is written only once it checks; a failed run keeps
/// its last attempt as OUT.rejected.scn, and a run that succeeds removes an earlier run's.
pub struct Dest<'a> {
    out: &'a Path,
    rejected: PathBuf,
}

impl<'a> Dest<'a> {
    pub fn new(out: &'a Path) -> Self {
        Dest { out, rejected: out.with_extension("rejected.scn") }
    }

    /// The file name diagnostics use: the `-o` file's.
    pub fn name(&self) -> String {
        self.out.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "scene.scn".into())
    }

    /// Where `use` imports resolve: the `-o` file's directory.
    pub fn base(&self) -> &Path {
        self.out.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."))
    }

    /// Write OUT.transcript.json; a failure to is shown and the run goes on.
    pub fn transcript(&self, v: &serde_json::Value) {
        let t = self.out.with_extension("transcript.json");
        let bytes = serde_json::to_vec_pretty(v).expect("a JSON value serialises");
        match write_file(&t, &bytes) {
            Ok(_) => eprintln!("transcript: {}", t.display()),
            Err(e) => {
                show(&[Diagnostic::error("E0401", format!("cannot write {}: {e}", t.display()))], &SourceMap::default())
            }
        }
    }

    /// Write the checked scenario to OUT and remove a rejected attempt an earlier run left: it
    /// would now mislead.
    pub fn accept(&self, text: &str) -> Result<(), Failure> {
        write_file(self.out, text.as_bytes())
            .map_err(|e| Diagnostic::error("E0401", format!("cannot write {}: {e}", self.out.display())))?;
        let _ = std::fs::remove_file(&self.rejected);
        Ok(())
    }

    /// Keep a rejected attempt as OUT.rejected.scn and show why it was rejected: re-checked under
    /// the kept file's name, so the spans point into it. Diagnostics without a file (no scenario
    /// in the reply, no usable conflict) are the better explanation and are shown as they are,
    /// as they are when the kept file checks. Returns where the attempt is, for the final help.
    pub fn reject(&self, text: &str, diags: Vec<Diagnostic>, sources: SourceMap) -> String {
        let kept = write_file(&self.rejected, text.as_bytes());
        let mut named = SourceMap::default();
        let (diags, sources) = match &kept {
            Ok(_) if sources.files.is_empty() => (diags, sources),
            Ok(_) => match rocc::check::check_text(&self.rejected.display().to_string(), text, self.base(), &mut named)
                .and_then(|s| rocc::compile::front(s, None))
            {
                Err(d) => (d, named),
                Ok(_) => (diags, sources),
            },
            Err(_) => (diags, sources),
        };
        show(&diags, &sources);
        match kept {
            Ok(_) => format!("the last attempt is kept in {}", self.rejected.display()),
            Err(e) => format!("the last attempt could not be kept ({e})"),
        }
    }

    /// After a run that ended in an error, keep its last attempt, if any, to look at.
    pub fn keep_last(&self, last: Option<&String>) {
        if let Some(last) = last
            && write_file(&self.rejected, last.as_bytes()).is_ok()
        {
            eprintln!("the last attempt is kept in {}", self.rejected.display());
        }
    }
}
