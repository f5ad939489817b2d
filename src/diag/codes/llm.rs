//! E06xx: the LLM front end (`rocc text`): the HTTP client, the model's replies, the repair loop.

use super::Code;

pub const CODES: &[Code] = &[
    Code {
        code: "E0601",
        title: "LLM endpoint unreachable",
        explanation: "`rocc text` could not connect to the model server: nothing listens at the address, the\n\
host name does not resolve, or the connection was reset. Start the server first and pass its\n\
OpenAI-compatible base URL:\n
    rocc text \"...\" -o scene.scn --server llamacpp --endpoint http://127.0.0.1:8080/v1\n\n\
The endpoint may also come from ROCC_LLM_ENDPOINT. docs/llm.md has the server commands.",
    },
    Code {
        code: "E0602",
        title: "LLM request timed out",
        explanation: "The model server accepted the request but did not answer within `--timeout` seconds\n\
(default 120). Long grammar-constrained generations on a CPU can be slow: raise `--timeout`, lower\n\
`--max-tokens`, or use a smaller model. Timeouts are not retried: the server is probably busy.\n
    $ rocc text \"a deer crosses at dusk\" -o deer.scn --timeout 600   // give a slow CPU server more time",
    },
    Code {
        code: "E0603",
        title: "LLM server returned an HTTP error",
        explanation: "The server answered with an error status (or a JSON `error` object). 429 and 5xx are\n\
retried `--retries` times with exponential backoff (honouring `Retry-After`) before this error;\n\
other statuses are reported at once. 401/403: pass `--api-key` or set ROCC_LLM_API_KEY. 404:\n\
the endpoint should end in `/v1` and the model name must exist on the server. 400: the server\n\
rejected the request body; if it names `grammar` or `structured_outputs`, the server does not\n\
support grammar-constrained decoding in that form: pick the right `--server` or pass\n\
`--no-grammar`.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --endpoint https://api.example.com/v1   // error: 401 Unauthorized
    $ rocc text \"a van cuts in\" -o cut_in.scn --endpoint https://api.example.com/v1 --api-key $KEY   // fine",
    },
    Code {
        code: "E0604",
        title: "LLM reply is not a chat completion",
        explanation: "The server's reply is not JSON, or is JSON without the OpenAI chat-completion shape\n\
(`choices[0].message.content`). The endpoint is probably not an OpenAI-compatible\n\
`/v1/chat/completions` (a web page, a proxy error, another API). Check `--endpoint`.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --endpoint http://127.0.0.1:8080   // error if that serves a web page
    $ rocc text \"a van cuts in\" -o cut_in.scn --endpoint http://127.0.0.1:8080/v1   // fine",
    },
    Code {
        code: "E0605",
        title: "LLM reply is empty",
        explanation: "The reply has no choices, or the message content is empty or null. Some servers do this\n\
when the prompt exceeds the context window or when a grammar admits no continuation. Use a model\n\
with a larger context, or look at the exchange with `--transcript`.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --transcript   // saves every request and reply beside the output",
    },
    Code {
        code: "E0606",
        title: "LLM reply truncated",
        explanation: "The model stopped because it hit `--max-tokens` (`finish_reason: length`), so its text is\n\
incomplete. Raise `--max-tokens`; a model that keeps generating whitespace or comments under a\n\
grammar constraint is a sign the model is too small for the task.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --max-tokens 4096   // room for the whole scenario",
    },
    Code {
        code: "E0607",
        title: "LLM refused",
        explanation: "The model refused the request (an OpenAI `refusal` field, or `finish_reason:\n\
content_filter`). Rephrase the sentence; scenario descriptions of crashes and emergencies are\n\
ordinary traffic-safety engineering, which saying so in the sentence often helps with.\n
    $ rocc text \"a van cuts in front of the ego, for a safety test\" -o cut_in.scn",
    },
    Code {
        code: "E0608",
        title: "LLM reply is not UTF-8",
        explanation: "The reply body is not valid UTF-8 text. rocc reads replies as JSON, which is UTF-8 by\n\
definition; the server or a proxy in between is misconfigured.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn   // error if a proxy answers in Latin-1",
    },
    Code {
        code: "E0609",
        title: "LLM reply too long",
        explanation: "The reply body is over 4 MiB or the message content over 64 KiB: far more than any scenario\n\
needs. rocc stops reading rather than buffer a runaway generation; lower `--max-tokens`.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --max-tokens 2048   // bound the generation",
    },
    Code {
        code: "E0610",
        title: "LLM reply is not a scenario",
        explanation: "The model answered with text that holds no `scenario NAME { ... }` block (prose, an\n\
apology, another language). In the repair loop this counts as a failed attempt: the diagnostic is\n\
sent back and the model is asked again, up to `--max-repairs` times. Grammar-constrained decoding\n\
(`--server vllm` or `llamacpp`) makes this impossible.\n
    I'm sorry, I can only describe scenes in English.   // error: no `scenario` block in the reply",
    },
    Code {
        code: "E0611",
        title: "LLM did not produce a usable scene schema",
        explanation: "The schema stage asks for one JSON object (road template, agents with kinds and\n\
placements, a brief). The reply was not such an object after `--max-repairs` corrections: not\n\
JSON, missing fields, or values of the wrong type. The last reply and the parse error are shown;\n\
`--transcript` keeps the whole exchange.\n
    { \"road\": \"four_way\", \"agents\": \"two cars\" }   // error: `agents` must be an array",
    },
    Code {
        code: "E0612",
        title: "LLM goal reply unusable",
        explanation: "The goal stage (\"traffic director\") asks for `goal { ... }` blocks in the goal\n\
vocabulary. A reply without a block that parses, or naming agents that do not exist, is corrected\n\
up to `--max-repairs` times; after that the agent keeps its initial speed and no goal (a warning)\n\
and the checker has the last word on the emitted file.\n
    goal { cutter: change_lane left }   // fine, when the scene declares `cutter`
    goal { truck: stop }                // error if the scene has no agent `truck`",
    },
    Code {
        code: "E0613",
        title: "generated scenario still fails to check",
        explanation: "The emitted `.scn` did not check (syntax, names, units, placement or rollout) and\n\
`--max-repairs` rounds of sending the diagnostics back did not fix it. Nothing is written to\n\
`-o`; the last attempt is kept beside it as `NAME.rejected.scn` with its diagnostics, so it can be\n\
fixed by hand (`rocc check NAME.rejected.scn`) or the run repeated with a stronger model.\n
    $ rocc check cut_in.rejected.scn   // the last attempt, with its diagnostics",
    },
    Code {
        code: "E0614",
        title: "bad `rocc text` option",
        explanation: "An option of `rocc text` is unusable: the endpoint is not an http(s) URL (https needs the\n\
`https` build feature), `--model` is missing for a server that needs one, `--density` or\n\
`--randomness` is outside 0..1, the `--image` file cannot be read or is not PNG/JPEG/WebP/GIF, or\n\
the sentence is empty.\n
    $ rocc text \"a van cuts in\" -o cut_in.scn --density 1.5   // error: --density must be in 0..1",
    },
];
