//! `render` on several servers (`--server A --server B`, or
//! `PATHSTREAM_URL=A,B`): one image, a session on each server with the same
//! scene, size and settings, polled together; their linear frames are
//! merged here, weighted by samples per pixel ([`pathstream_client::merge`]).
//!
//! - Seeds: the k-th session made gets `seed + k` (`--seed`, else 0, the
//!   server's default): the reachable servers in the order given, then any
//!   top-up session. The sampler hashes the seed, so neighbouring seeds are
//!   independent streams.
//! - An spp halt is split: each of N servers renders `ceil(spp / N)`, so the
//!   merged image has at least `spp` and the same samples however fast each
//!   server is (a fast server waits for a slow one).
//! - A time halt goes to every server as it is: the merged image is what
//!   they rendered in that time.
//! - A target error goes to every server as it is (a merged image reaches it
//!   before any of its parts does); the render stops when the merged estimate
//!   ([`combined_error`], from each server's status) reaches it, from 8 spp
//!   as on a server.
//! - A server that cannot be reached at the start, or fails mid-render
//!   (unreachable, its session gone, its device failed), is dropped with a
//!   warning naming it and its samples are lost; with an spp halt, the
//!   servers left render the missing samples in one more session each.
//!   With no server left the command fails: exit code 4 if the last one
//!   lost was unreachable, 3 otherwise.
//! - Adaptive sampling is allowed: the weights are then the servers' mean
//!   spp (see [`pathstream_client::merge`] for what that costs).
//! - `.pfm` is written as merged; `.png` is tone-mapped here exactly as the
//!   server makes `frame.png`.

use super::guard::{Interrupt, CREATE_GRACE};
use super::{extension, outln, session_request, write, CreateArgs, Failure, RenderArgs};
use futures_util::future::join_all;
use indicatif::{ProgressBar, ProgressStyle};
use pathstream_client::merge::{combined_error, merge};
use pathstream_client::{Client, ClientError, CreateSession, LinearFrame, SessionStatus};
use std::time::Duration;
use tokio::task::JoinHandle;

/// How often the servers are asked for their status.
const POLL: Duration = Duration::from_millis(200);
/// A server that does not answer a status request in this long is dropped.
const POLL_TIMEOUT: Duration = Duration::from_secs(10);
/// The server checks a target error from this many samples per pixel on.
const MIN_SPP_FOR_TARGET_ERROR: u64 = 8;

struct Server {
    client: Client,
    /// What to create on it (its model files uploaded to it).
    request: Option<CreateSession>,
    /// Reachable and not failed: may render (more).
    takes_work: bool,
}

/// A session rendering part of the image.
struct Part {
    server: usize,
    /// Its spp halt, when the render has one.
    share: Option<u64>,
    status: SessionStatus,
    /// False once its server failed it: its samples are lost.
    live: bool,
}

/// A session being created, in its own task so that a Ctrl-C that drops the
/// render cannot lose a session the server made: cleanup waits for it.
struct Pending {
    server: usize,
    share: Option<u64>,
    task: JoinHandle<Result<SessionStatus, ClientError>>,
}

struct Fleet {
    servers: Vec<Server>,
    parts: Vec<Part>,
    pending: Vec<Pending>,
    next_seed: u64,
    bar: ProgressBar,
    /// Exit code and message of the last server lost.
    lost: Option<(u8, String)>,
    /// Session warnings printed (each once, however many servers say it).
    warnings: Vec<String>,
    short_warned: bool,
}

/// Renders `args` on all of `clients` (two or more) into one image.
pub async fn render(clients: Vec<Client>, args: &RenderArgs) -> Result<(), Failure> {
    let kind = extension(&args.out)?;
    let mut interrupt = Interrupt::install()?;
    let bar = ProgressBar::new(0).with_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} spp  {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut fleet = Fleet {
        servers: clients
            .into_iter()
            .map(|client| Server {
                client,
                request: None,
                takes_work: true,
            })
            .collect(),
        parts: Vec::new(),
        pending: Vec::new(),
        next_seed: 0,
        bar,
        lost: None,
        warnings: Vec::new(),
        short_warned: false,
    };
    let result = tokio::select! {
        biased;
        () = interrupt.received() => Err(Failure(130, "interrupted".into())),
        r = work(&mut fleet, args, kind) => r,
    };
    fleet.cleanup().await;
    result
}

/// The halt conditions of the merged image.
struct Halts {
    spp: Option<u64>,
    target_error: Option<f64>,
}

async fn work(fleet: &mut Fleet, args: &RenderArgs, kind: &str) -> Result<(), Failure> {
    fleet.probe().await;
    let halts = fleet.prepare(&args.create).await?;
    let n = fleet.servers.iter().filter(|s| s.takes_work).count() as u64;
    if n == 0 {
        return Err(fleet.none_left());
    }
    fleet.bar.set_length(halts.spp.unwrap_or(0));
    let share = halts.spp.map(|spp| spp.div_ceil(n));
    let all: Vec<usize> = (0..fleet.servers.len())
        .filter(|&i| fleet.servers[i].takes_work)
        .collect();
    fleet.create(&all, share).await;
    loop {
        fleet.poll().await;
        if let Some(spp) = halts.spp {
            fleet.top_up(spp).await;
        }
        if !fleet.parts.iter().any(|p| p.live) {
            return Err(fleet.none_left());
        }
        if fleet.done(&halts) {
            break;
        }
        tokio::time::sleep(POLL).await;
    }
    fleet.bar.finish_and_clear();
    let frames = fleet.frames().await;
    if frames.is_empty() {
        return Err(fleet.none_left());
    }
    let parts: Vec<LinearFrame> = frames.iter().map(|(_, f)| f.clone()).collect();
    let merged = merge(&parts).map_err(|e| Failure(3, format!("cannot merge the frames: {e}")))?;
    let bytes = match kind {
        "png" => merged
            .image
            .encode_png()
            .map_err(|e| Failure(1, e.to_string()))?,
        _ => merged.image.encode_pfm(),
    };
    write(&args.out, &bytes)?;
    outln!("{}", fleet.summary(&frames, &merged, args))?;
    Ok(())
}

impl Fleet {
    fn url(&self, server: usize) -> &str {
        self.servers[server].client.base_url()
    }

    fn warn(&self, message: &str) {
        self.bar.suspend(|| eprintln!("warning: {message}"));
    }

    /// Drops `server` from the render for `e`.
    fn lose(&mut self, server: usize, e: &Failure) {
        self.servers[server].takes_work = false;
        let message = format!("{}: {}", self.url(server), e.1);
        self.warn(&format!(
            "{message}; dropped, going on with the other servers"
        ));
        self.lost = Some((e.0, message));
    }

    fn none_left(&self) -> Failure {
        let (code, last) = self
            .lost
            .clone()
            .unwrap_or((3, "no server took the render".into()));
        Failure(code, format!("no server left to render on (last: {last})"))
    }

    /// Asks every server for its health; drops those that do not answer.
    async fn probe(&mut self) {
        let answers = join_all(self.servers.iter().map(|s| s.client.health())).await;
        for (i, answer) in answers.into_iter().enumerate() {
            if let Err(e) = answer {
                self.lose(i, &e.into());
            }
        }
    }

    /// The session request for each server left; its halts. A problem on
    /// this side (a scene file) ends the render, a server's refusal drops it.
    async fn prepare(&mut self, args: &CreateArgs) -> Result<Halts, Failure> {
        let requests = join_all(self.servers.iter().map(|s| async {
            if s.takes_work {
                Some(session_request(&s.client, args, true).await)
            } else {
                None
            }
        }))
        .await;
        let mut halts = Halts {
            spp: None,
            target_error: None,
        };
        for (i, request) in requests.into_iter().enumerate() {
            match request {
                None => {}
                Some(Err(e)) if e.0 == 2 => return Err(e),
                Some(Err(e)) => self.lose(i, &e),
                Some(Ok(req)) => {
                    if let Some(q) = &req.quality {
                        halts.spp = q.spp.flatten();
                        halts.target_error = q.target_error.flatten();
                        self.next_seed = q.seed.unwrap_or(0);
                    }
                    self.servers[i].request = Some(req);
                }
            }
        }
        Ok(halts)
    }

    /// Creates one session on each of `servers`, each with the next seed and
    /// `share` as its spp halt.
    async fn create(&mut self, servers: &[usize], share: Option<u64>) {
        for &server in servers {
            let Some(mut req) = self.servers[server].request.clone() else {
                continue;
            };
            let mut quality = req.quality.take().unwrap_or_default();
            quality.seed = Some(self.next_seed);
            self.next_seed = self.next_seed.wrapping_add(1);
            if share.is_some() {
                quality.spp = Some(share);
            }
            req.quality = Some(quality);
            let client = self.servers[server].client.clone();
            let task = tokio::spawn(async move { client.create_session(&req).await });
            self.pending.push(Pending {
                server,
                share,
                task,
            });
        }
        while let Some(p) = self.pending.last_mut() {
            let created = (&mut p.task).await;
            let Some(p) = self.pending.pop() else { break };
            match created {
                Ok(Ok(status)) => {
                    for w in &status.warnings {
                        if !self.warnings.contains(w) {
                            self.warn(w);
                            self.warnings.push(w.clone());
                        }
                    }
                    self.parts.push(Part {
                        server: p.server,
                        share: p.share,
                        status,
                        live: true,
                    });
                }
                Ok(Err(e)) => self.lose(p.server, &e.into()),
                Err(e) => self.lose(p.server, &Failure(1, e.to_string())),
            }
        }
    }

    /// Updates every live part's status; drops the servers that fail.
    async fn poll(&mut self) {
        let answers = join_all(self.parts.iter().filter(|p| p.live).map(|p| {
            let client = &self.servers[p.server].client;
            tokio::time::timeout(POLL_TIMEOUT, client.session(&p.status.id))
        }))
        .await;
        let live: Vec<usize> = (0..self.parts.len())
            .filter(|&i| self.parts[i].live)
            .collect();
        for (i, answer) in live.into_iter().zip(answers) {
            let server = self.parts[i].server;
            let failure = match answer {
                Err(_) => Failure(4, format!("no answer in {} s", POLL_TIMEOUT.as_secs())),
                Ok(Err(e)) => e.into(),
                Ok(Ok(status)) => match &status.failure {
                    Some(f) => Failure(3, format!("rendering failed on the server: {f}")),
                    None => {
                        self.parts[i].status = status;
                        continue;
                    }
                },
            };
            self.parts[i].live = false;
            self.lose(server, &failure);
        }
        let live = self.parts.iter().filter(|p| p.live);
        let (spp, rate) = live.fold((0, 0.0), |(n, r), p| {
            (n + p.status.spp, r + p.status.samples_per_sec)
        });
        self.bar.set_position(spp);
        let servers = (0..self.servers.len())
            .filter(|&s| self.parts.iter().any(|p| p.live && p.server == s))
            .count();
        self.bar.set_message(format!(
            "error {}  {:.2} M paths/s  {servers} servers",
            percent(self.estimate()),
            rate / 1e6,
        ));
    }

    /// With an spp halt: when the live parts' shares fall short of `spp`
    /// (a server was lost), one more session on each server left renders
    /// the rest.
    async fn top_up(&mut self, spp: u64) {
        let planned: u64 = self
            .parts
            .iter()
            .filter(|p| p.live)
            .filter_map(|p| p.share)
            .sum();
        let missing = spp.saturating_sub(planned);
        if missing == 0 {
            return;
        }
        let able: Vec<usize> = (0..self.servers.len())
            .filter(|&s| self.servers[s].takes_work)
            .filter(|&s| self.parts.iter().any(|p| p.live && p.server == s))
            .collect();
        if able.is_empty() {
            if !self.short_warned && planned > 0 {
                self.warn(&format!(
                    "the merged image will have {planned} of {spp} spp: no server left to render the rest"
                ));
                self.short_warned = true;
            }
            return;
        }
        let share = missing.div_ceil(able.len() as u64);
        let on = match able.len() {
            1 => "on the server left".to_owned(),
            n => format!("{share} on each of the {n} servers left"),
        };
        self.warn(&format!("{missing} spp lost: rendering them again {on}"));
        self.create(&able, Some(share)).await;
    }

    /// The merged error estimate from the live parts' statuses.
    fn estimate(&self) -> Option<f64> {
        let parts: Vec<(u64, Option<f64>)> = self
            .parts
            .iter()
            .filter(|p| p.live)
            .map(|p| (p.status.spp, p.status.error_estimate))
            .collect();
        combined_error(&parts)
    }

    /// Every live part halted, or the merged image at its target error.
    fn done(&self, halts: &Halts) -> bool {
        let mut live = self.parts.iter().filter(|p| p.live).peekable();
        if live.peek().is_none() {
            return false;
        }
        let spp: u64 = live.clone().map(|p| p.status.spp).sum();
        live.all(|p| p.status.halted())
            || halts.target_error.is_some_and(|t| {
                spp >= MIN_SPP_FOR_TARGET_ERROR && self.estimate().is_some_and(|e| e <= t)
            })
    }

    /// Each live part's frame, with at least the samples its status said.
    async fn frames(&mut self) -> Vec<(usize, LinearFrame)> {
        let live: Vec<usize> = (0..self.parts.len())
            .filter(|&i| self.parts[i].live)
            .collect();
        let answers = join_all(live.iter().map(|&i| {
            let p = &self.parts[i];
            let client = &self.servers[p.server].client;
            client.linear_frame(&p.status.id, Some(p.status.spp), None)
        }))
        .await;
        let mut frames = Vec::new();
        for (i, answer) in live.into_iter().zip(answers) {
            let server = self.parts[i].server;
            match answer {
                Ok(frame) => frames.push((server, frame)),
                Err(e) => {
                    self.parts[i].live = false;
                    self.lose(server, &e.into());
                }
            }
        }
        frames
    }

    /// What `render` prints: the image, the spp of all and of each server,
    /// the merged error estimate, the output.
    fn summary(
        &self,
        frames: &[(usize, LinearFrame)],
        merged: &pathstream_client::merge::Merged,
        args: &RenderArgs,
    ) -> String {
        let first = self.parts.iter().find(|p| p.live).map(|p| &p.status);
        let (scene, adaptive) =
            first.map_or(("?", false), |s| (s.scene.as_str(), s.quality.adaptive));
        let unit = if adaptive { "spp (mean)" } else { "spp" };
        let mut servers: Vec<(usize, u64)> = Vec::new();
        for (server, f) in frames {
            match servers.iter_mut().find(|(s, _)| s == server) {
                Some((_, spp)) => *spp += f.spp,
                None => servers.push((*server, f.spp)),
            }
        }
        servers.sort_unstable();
        let each: Vec<String> = servers
            .iter()
            .map(|&(s, spp)| format!("{}: {spp} spp", self.url(s)))
            .collect();
        let rate: f64 = self
            .parts
            .iter()
            .filter(|p| p.live)
            .map(|p| p.status.samples_per_sec)
            .sum();
        let plural = if servers.len() == 1 { "" } else { "s" };
        format!(
            "{scene} {}x{}: {} {unit} from {} server{plural} ({}), error estimate {} (merged), \
             {:.2} M paths/s -> {}",
            merged.image.width,
            merged.image.height,
            merged.spp,
            servers.len(),
            each.join(", "),
            percent(merged.error_estimate),
            rate / 1e6,
            args.out.display()
        )
    }

    /// Deletes every session made (waiting briefly for those still being
    /// made); a live one that cannot be deleted is a warning.
    async fn cleanup(&mut self) {
        self.bar.finish_and_clear();
        for p in std::mem::take(&mut self.pending) {
            if let Ok(Ok(Ok(status))) = tokio::time::timeout(CREATE_GRACE, p.task).await {
                self.parts.push(Part {
                    server: p.server,
                    share: p.share,
                    status,
                    live: true,
                });
            }
        }
        let deleted = join_all(self.parts.iter().map(|p| {
            let client = &self.servers[p.server].client;
            client.delete_session(&p.status.id)
        }))
        .await;
        for (p, deleted) in self.parts.iter().zip(deleted) {
            if let (true, Err(e)) = (p.live, deleted) {
                self.warn(&format!(
                    "{}: session {} not deleted: {e}",
                    self.url(p.server),
                    p.status.id
                ));
            }
        }
    }
}

fn percent(e: Option<f64>) -> String {
    e.map_or("n/a".into(), |e| format!("{:.2}%", e * 100.0))
}
