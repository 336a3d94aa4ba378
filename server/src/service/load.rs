//! How busy a render worker is: the fraction of the last [`WINDOW`] of wall
//! time it spent rendering, as `/api/health` reports it (`"busy"`, 0..1) so
//! that a proxy or an operator can see which box has room.
//!
//! Busy time is kept in [`SLOTS`] slots of [`SLOT`] each, a pass's time
//! split over the slots it spans; a pass still running counts up to now. So
//! the figure follows a box that starts or stops rendering within about one
//! window, and never depends on how often it is asked for.

use std::sync::{Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// The length of one slot.
pub const SLOT: Duration = Duration::from_millis(500);
/// How many slots the window holds.
pub const SLOTS: usize = 10;
/// The span `busy` is measured over.
pub const WINDOW: Duration = Duration::from_millis(500 * SLOTS as u64);

/// One worker's load, as `/api/health` reports it under `"load"` (`busy`
/// and `samples_per_sec` over the last [`WINDOW`]).
pub use pathstream_wire::WorkerLoad;

/// A per-worker series: name, type, help, and the value of one worker.
type Series = (
    &'static str,
    &'static str,
    &'static str,
    fn(&WorkerLoad) -> String,
);

/// The workers' busy fractions and sessions as Prometheus gauges, by
/// worker number and backend (no device names: `/metrics` holds counts).
pub fn prometheus(loads: &[WorkerLoad]) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# HELP pathstream_worker_busy_ratio Fraction of the last 5 s each worker spent rendering.\n# TYPE pathstream_worker_busy_ratio gauge"
    );
    for (i, l) in loads.iter().enumerate() {
        let _ = writeln!(
            out,
            "pathstream_worker_busy_ratio{{worker=\"{i}\",backend=\"{}\"}} {}",
            l.backend, l.busy
        );
    }
    let lines: [Series; 3] = [
        (
            "pathstream_worker_sessions",
            "gauge",
            "Sessions placed on each worker.",
            |l| l.sessions.to_string(),
        ),
        (
            "pathstream_worker_samples_per_second",
            "gauge",
            "Camera paths per second each worker rendered over the last 5 s.",
            |l| format!("{:.0}", l.samples_per_sec),
        ),
        (
            "pathstream_worker_samples_total",
            "counter",
            "Camera paths each worker rendered.",
            |l| l.samples.to_string(),
        ),
    ];
    for (name, kind, help, value) in lines {
        let _ = writeln!(out, "# HELP {name} {help}\n# TYPE {name} {kind}");
        for (i, l) in loads.iter().enumerate() {
            let _ = writeln!(
                out,
                "{name}{{worker=\"{i}\",backend=\"{}\"}} {}",
                l.backend,
                value(l)
            );
        }
    }
    out
}

#[derive(Clone, Copy, Debug, Default)]
struct Slot {
    /// Which slot since the meter's origin this holds (stale when older than the window).
    index: u64,
    busy: Duration,
    /// Camera paths finished in the slot.
    samples: u64,
}

#[derive(Debug)]
struct Inner {
    slots: [Slot; SLOTS],
    /// When the pass in flight began, if one is.
    running_since: Option<Instant>,
}

/// Busy time of one worker over a rolling window.
#[derive(Debug)]
pub struct BusyMeter {
    origin: Instant,
    inner: Mutex<Inner>,
}

impl BusyMeter {
    /// A meter that was idle until `origin`, and counts from there.
    pub fn new(origin: Instant) -> Self {
        Self {
            origin,
            inner: Mutex::new(Inner {
                slots: [Slot::default(); SLOTS],
                running_since: None,
            }),
        }
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn slot_index(&self, t: Instant) -> u64 {
        let since = t.saturating_duration_since(self.origin);
        (since.as_nanos() / SLOT.as_nanos()) as u64
    }

    fn slot_start(&self, index: u64) -> Instant {
        self.origin + SLOT * u32::try_from(index).unwrap_or(u32::MAX)
    }

    /// The worker starts rendering at `now`.
    pub fn begin(&self, now: Instant) {
        self.lock().running_since = Some(now);
    }

    /// The worker stops rendering at `now`: the time since [`begin`](Self::begin)
    /// goes into the slots it spans.
    pub fn end(&self, now: Instant) {
        let mut inner = self.lock();
        let Some(since) = inner.running_since.take() else {
            return;
        };
        // Only the part inside the window can ever be reported.
        let now_index = self.slot_index(now);
        let oldest = now_index.saturating_sub(SLOTS as u64 - 1);
        let mut from = since.max(self.slot_start(oldest));
        while from < now {
            let index = self.slot_index(from);
            let to = now.min(self.slot_start(index + 1));
            if to <= from {
                break; // a slot past the representable range: nothing more to count
            }
            let slot = &mut inner.slots[(index % SLOTS as u64) as usize];
            if slot.index != index {
                *slot = Slot {
                    index,
                    ..Slot::default()
                };
            }
            slot.busy += to - from;
            from = to;
        }
    }

    /// Counts `paths` camera paths finished at `now`.
    pub fn count(&self, now: Instant, paths: u64) {
        let index = self.slot_index(now);
        let mut inner = self.lock();
        let slot = &mut inner.slots[(index % SLOTS as u64) as usize];
        if slot.index != index {
            *slot = Slot {
                index,
                ..Slot::default()
            };
        }
        slot.samples += paths;
    }

    /// Camera paths per second over the window before `now` (over the time
    /// since the origin while that is shorter than the window).
    pub fn rate(&self, now: Instant) -> f64 {
        let inner = self.lock();
        let now_index = self.slot_index(now);
        let oldest = now_index.saturating_sub(SLOTS as u64 - 1);
        let span = now.saturating_duration_since(self.slot_start(oldest).max(self.origin));
        let samples: u64 = (inner.slots.iter())
            .filter(|s| (oldest..=now_index).contains(&s.index))
            .map(|s| s.samples)
            .sum();
        match span.is_zero() {
            true => 0.0,
            false => samples as f64 / span.as_secs_f64(),
        }
    }

    /// The fraction of the window before `now` spent rendering (of the
    /// time since the origin while that is shorter than the window).
    pub fn fraction(&self, now: Instant) -> f64 {
        let inner = self.lock();
        let now_index = self.slot_index(now);
        let oldest = now_index.saturating_sub(SLOTS as u64 - 1);
        let window_start = self.slot_start(oldest);
        let span = now.saturating_duration_since(window_start);
        if span.is_zero() {
            return 0.0;
        }
        let recorded: Duration = inner
            .slots
            .iter()
            .filter(|s| (oldest..=now_index).contains(&s.index))
            .map(|s| s.busy)
            .sum();
        let running = inner.running_since.map_or(Duration::ZERO, |s| {
            now.saturating_duration_since(s.max(window_start))
        });
        ((recorded + running).as_secs_f64() / span.as_secs_f64()).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loads_read_as_prometheus_gauges() {
        let text = prometheus(&[WorkerLoad {
            backend: "cpu".into(),
            device: "rayon, 2 threads".into(),
            sessions: 3,
            busy: 0.25,
            samples_per_sec: 1234.4,
            samples: 99,
        }]);
        assert!(
            text.contains("pathstream_worker_busy_ratio{worker=\"0\",backend=\"cpu\"} 0.25\n"),
            "{text}"
        );
        assert!(
            text.contains("pathstream_worker_sessions{worker=\"0\",backend=\"cpu\"} 3\n"),
            "{text}"
        );
        assert!(
            text.contains(
                "pathstream_worker_samples_per_second{worker=\"0\",backend=\"cpu\"} 1234\n"
            ),
            "{text}"
        );
        assert!(
            text.contains("pathstream_worker_samples_total{worker=\"0\",backend=\"cpu\"} 99\n"),
            "{text}"
        );
        assert!(!text.contains("rayon"), "no device names: {text}");
    }

    fn ms(n: u64) -> Duration {
        Duration::from_millis(n)
    }

    #[test]
    fn the_rate_counts_paths_in_the_window_only() {
        let t0 = Instant::now();
        let m = BusyMeter::new(t0);
        assert_eq!(m.rate(t0), 0.0);
        m.count(t0 + ms(500), 1000);
        m.count(t0 + ms(1500), 3000);
        assert!((m.rate(t0 + ms(2000)) - 2000.0).abs() < 1e-6);
        // A window later the old slots are out: only the new paths count.
        m.count(t0 + ms(20_000), 5000);
        let r = m.rate(t0 + ms(20_000) + WINDOW / 2);
        assert!((r - 5000.0 / WINDOW.as_secs_f64()).abs() < 200.0, "{r}");
    }

    #[test]
    fn an_idle_meter_reads_zero_and_a_busy_one_one() {
        let t0 = Instant::now();
        let m = BusyMeter::new(t0);
        assert_eq!(m.fraction(t0), 0.0, "no time has passed");
        assert_eq!(m.fraction(t0 + ms(3000)), 0.0);
        // Busy from 3 s on, in 30 ms passes with no gaps.
        let mut t = t0 + ms(3000);
        while t < t0 + ms(12_000) {
            m.begin(t);
            t += ms(30);
            m.end(t);
        }
        let f = m.fraction(t);
        assert!((f - 1.0).abs() < 1e-9, "{f}");
    }

    #[test]
    fn busy_time_is_a_share_of_the_window_and_ages_out() {
        let t0 = Instant::now();
        let m = BusyMeter::new(t0);
        // 30 ms passes with 10 ms gaps for 20 s: 75% busy.
        let mut t = t0;
        while t < t0 + ms(20_000) {
            m.begin(t);
            t += ms(30);
            m.end(t);
            t += ms(10);
        }
        let f = m.fraction(t);
        assert!((f - 0.75).abs() < 0.02, "{f}");
        // Idle for half a window: about half of that.
        let f = m.fraction(t + WINDOW / 2);
        assert!((f - 0.375).abs() < 0.06, "{f}");
        // Idle for a whole window: nothing left.
        assert_eq!(m.fraction(t + WINDOW + SLOT), 0.0);
    }

    #[test]
    fn a_pass_in_flight_counts_up_to_now_and_a_long_one_fills_the_window() {
        let t0 = Instant::now();
        let m = BusyMeter::new(t0);
        m.begin(t0 + ms(1000));
        let f = m.fraction(t0 + ms(2000));
        assert!((f - 0.5).abs() < 1e-9, "busy for 1 s of the first 2: {f}");
        // A pass of a minute: the window is full, before and after it ends.
        assert!((m.fraction(t0 + ms(61_000)) - 1.0).abs() < 1e-9);
        m.end(t0 + ms(61_000));
        assert!((m.fraction(t0 + ms(61_000)) - 1.0).abs() < 1e-9);
        let f = m.fraction(t0 + ms(61_000) + WINDOW / 2);
        assert!((f - 0.5).abs() < 0.11, "{f}");
    }

    #[test]
    fn end_without_begin_and_times_before_the_origin_change_nothing() {
        let t0 = Instant::now() + ms(10_000);
        let m = BusyMeter::new(t0);
        m.end(t0 + ms(100));
        m.begin(t0 - ms(5000));
        m.end(t0 - ms(1000));
        assert_eq!(m.fraction(t0 + ms(1000)), 0.0);
    }
}
