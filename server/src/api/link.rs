//! One WebSocket's link as the stream sees it: frames in flight, how fast
//! they arrive, and the resolution of the first frames after a change.
//!
//! A client that acknowledges frames (`{"ack": SEQ}` for the `frame` number
//! of each stats message; the page does) gets the next frame only once it
//! has the last: one frame in flight end to end, so a camera change never
//! waits behind frames queued in the network, and the delivery time of each
//! frame (sent to acknowledged) measures the link. A client that never
//! acknowledges is paced by the socket accepting each frame, as before.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// An acknowledgement that does not come within this long is given up on
/// (the next frame goes out anyway).
pub const ACK_TIMEOUT: Duration = Duration::from_secs(5);

/// A frame sent and not yet acknowledged.
#[derive(Clone, Copy, Debug)]
struct InFlight {
    seq: u64,
    sent: Instant,
    bytes: usize,
}

/// What the stream knows of one socket's link.
#[derive(Debug, Default)]
pub struct Link {
    /// The client has acknowledged a frame: pace by acknowledgements.
    acking: bool,
    in_flight: Option<InFlight>,
    /// Arrivals (acknowledged, or accepted by the socket) in the last second.
    arrivals: VecDeque<Instant>,
    /// Bits per second of the last frames, sent to acknowledged (smoothed).
    rate_bps: Option<f64>,
    last_delivery: Option<Duration>,
}

impl Link {
    /// Whether the next frame may go out now.
    pub fn ready(&self) -> bool {
        !(self.acking && self.in_flight.is_some())
    }

    /// When to stop waiting for the acknowledgement in flight, if any.
    pub fn ack_deadline(&self) -> Option<Instant> {
        self.in_flight
            .filter(|_| self.acking)
            .map(|f| f.sent + ACK_TIMEOUT)
    }

    /// Frame `seq` of `bytes` starts going out at `at`.
    pub fn sending(&mut self, seq: u64, bytes: usize, at: Instant) {
        self.in_flight = Some(InFlight {
            seq,
            sent: at,
            bytes,
        });
    }

    /// The socket accepted the frame (a client that does not acknowledge:
    /// that is as far as the server can see it go).
    pub fn accepted(&mut self, at: Instant) {
        if !self.acking {
            self.in_flight = None;
            self.arrive(at);
        }
    }

    /// The client acknowledged frame `seq` at `at`; an acknowledgement of
    /// any other frame (late, or unknown) only turns pacing on.
    pub fn acked(&mut self, seq: u64, at: Instant) {
        self.acking = true;
        let Some(f) = self.in_flight.filter(|f| f.seq == seq) else {
            return;
        };
        self.in_flight = None;
        let took = at.saturating_duration_since(f.sent);
        self.last_delivery = Some(took);
        let bps = f.bytes as f64 * 8.0 / took.as_secs_f64().max(1e-4);
        self.rate_bps = Some(match self.rate_bps {
            Some(r) => 0.7 * r + 0.3 * bps,
            None => bps,
        });
        self.arrive(at);
    }

    /// The acknowledgement in flight did not come: send the next frame.
    pub fn give_up(&mut self) {
        self.in_flight = None;
    }

    fn arrive(&mut self, at: Instant) {
        self.arrivals.push_back(at);
        while self
            .arrivals
            .front()
            .is_some_and(|&t| at.saturating_duration_since(t) > Duration::from_secs(1))
        {
            self.arrivals.pop_front();
        }
    }

    /// Frames that arrived in the second before `now`.
    pub fn fps(&self, now: Instant) -> usize {
        self.arrivals
            .iter()
            .filter(|&&t| now.saturating_duration_since(t) <= Duration::from_secs(1))
            .count()
    }

    /// Delivery rate in Mbit/s (frame bytes over sent-to-acknowledged
    /// time, smoothed; it includes the round trip, so it reads low for
    /// small frames). None before an acknowledgement.
    pub fn mbps(&self) -> Option<f64> {
        self.rate_bps.map(|r| r / 1e6)
    }

    /// Sent-to-acknowledged time of the last acknowledged frame.
    pub fn last_delivery(&self) -> Option<Duration> {
        self.last_delivery
    }
}

/// The width to send frame number `nth` (0: the first) of a generation at,
/// with progressive resolution: a quarter of `width`, then half, then all
/// of it; a halted frame (the last) always whole.
pub fn progressive_width(width: u32, nth: u64, halted: bool) -> u32 {
    let divisor = match (halted, nth) {
        (true, _) | (_, 2..) => 1,
        (false, 0) => 4,
        (false, 1) => 2,
    };
    (width / divisor).max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_acknowledging_client_has_one_frame_in_flight() {
        let t0 = Instant::now();
        let mut link = Link::default();
        link.sending(1, 1000, t0);
        link.accepted(t0);
        assert!(link.ready(), "no acknowledgements yet: paced by the socket");
        assert_eq!(link.fps(t0), 1);
        link.sending(2, 125_000, t0);
        link.acked(2, t0 + Duration::from_millis(100));
        assert!(link.ready());
        // 1 Mbit in 100 ms: 10 Mbit/s.
        assert!((link.mbps().expect("rate") - 10.0).abs() < 1e-9);
        link.sending(3, 125_000, t0 + Duration::from_millis(200));
        link.accepted(t0 + Duration::from_millis(201));
        assert!(!link.ready(), "frame 3 not acknowledged");
        assert_eq!(
            link.ack_deadline(),
            Some(t0 + Duration::from_millis(200) + ACK_TIMEOUT)
        );
        link.acked(2, t0 + Duration::from_millis(300));
        assert!(!link.ready(), "a stale acknowledgement releases nothing");
        link.give_up();
        assert!(link.ready());
    }

    #[test]
    fn progressive_resolution_steps_up_and_ends_whole() {
        assert_eq!(progressive_width(1920, 0, false), 480);
        assert_eq!(progressive_width(1920, 1, false), 960);
        assert_eq!(progressive_width(1920, 2, false), 1920);
        assert_eq!(progressive_width(1920, 0, true), 1920);
        assert_eq!(progressive_width(3, 0, false), 1);
    }
}
