//! Counters for `/metrics` (Prometheus text format).

use std::fmt::Write;
use std::sync::atomic::{AtomicU64, Ordering};

#[derive(Debug, Default)]
pub struct Metrics {
    pub samples_cpu: AtomicU64,
    pub samples_opencl: AtomicU64,
    pub frames_sent: AtomicU64,
    pub frames_dropped: AtomicU64,
    pub rejected_samples: AtomicU64,
    pub sessions_created: AtomicU64,
    pub handler_panics: AtomicU64,
    /// Connections closed at once: `--max-connections` reached.
    pub refused_total_limit: AtomicU64,
    /// Connections closed at once: too many from the client's address.
    pub refused_per_address: AtomicU64,
    /// Connections closed because no whole request head came in time.
    pub head_timeouts: AtomicU64,
}

impl Metrics {
    pub fn add_samples(&self, backend: &str, paths: u64) {
        let counter = if backend == "opencl" {
            &self.samples_opencl
        } else {
            &self.samples_cpu
        };
        counter.fetch_add(paths, Ordering::Relaxed);
    }

    pub fn render(&self, sessions: usize) -> String {
        let get = |c: &AtomicU64| c.load(Ordering::Relaxed);
        let mut out = String::new();
        let mut metric = |name: &str, kind: &str, help: &str, lines: &[(String, u64)]| {
            let _ = writeln!(out, "# HELP {name} {help}\n# TYPE {name} {kind}");
            for (labels, v) in lines {
                let _ = writeln!(out, "{name}{labels} {v}");
            }
        };
        metric(
            "pathstream_sessions",
            "gauge",
            "Render sessions open.",
            &[(String::new(), sessions as u64)],
        );
        metric(
            "pathstream_sessions_created_total",
            "counter",
            "Render sessions created.",
            &[(String::new(), get(&self.sessions_created))],
        );
        metric(
            "pathstream_samples_total",
            "counter",
            "Camera paths rendered, by backend.",
            &[
                ("{backend=\"cpu\"}".into(), get(&self.samples_cpu)),
                ("{backend=\"opencl\"}".into(), get(&self.samples_opencl)),
            ],
        );
        metric(
            "pathstream_frames_sent_total",
            "counter",
            "Frames sent over WebSockets.",
            &[(String::new(), get(&self.frames_sent))],
        );
        metric(
            "pathstream_frames_dropped_total",
            "counter",
            "Frames a WebSocket client skipped because a newer one was ready.",
            &[(String::new(), get(&self.frames_dropped))],
        );
        metric(
            "pathstream_handler_panics_total",
            "counter",
            "Request handlers that panicked (each answered 500).",
            &[(String::new(), get(&self.handler_panics))],
        );
        metric(
            "pathstream_connections_refused_total",
            "counter",
            "Connections closed at once, by the limit they met.",
            &[
                (
                    "{limit=\"max_connections\"}".into(),
                    get(&self.refused_total_limit),
                ),
                (
                    "{limit=\"per_address\"}".into(),
                    get(&self.refused_per_address),
                ),
            ],
        );
        metric(
            "pathstream_request_head_timeouts_total",
            "counter",
            "Connections closed because no whole request head came within --header-timeout-s.",
            &[(String::new(), get(&self.head_timeouts))],
        );
        metric(
            "pathstream_rejected_samples_total",
            "counter",
            "Samples rejected as NaN or infinite.",
            &[(String::new(), get(&self.rejected_samples))],
        );
        out
    }
}
