//! Connections: accepted under caps (in total and per client address) so
//! that slow or idle clients cannot use up the process's file descriptors,
//! each with a deadline for its request head (a client that sends a head a
//! byte at a time is dropped), TCP_NODELAY, served by hyper's HTTP/1 with
//! upgrades (WebSockets), and shut down gracefully.

use crate::service::metrics::Metrics;
use crate::service::ConnectionLimits;
use axum::Router;
use hyper_util::rt::{TokioIo, TokioTimer};
use hyper_util::service::TowerToHyperService;
use std::collections::HashMap;
use std::future::Future;
use std::net::IpAddr;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::net::TcpListener;
use tokio::sync::{mpsc, watch, OwnedSemaphorePermit, Semaphore};

/// Raises the soft limit on open files to the hard one (a server holds a
/// descriptor per connection); returns the limit now in force.
pub fn raise_file_limit() -> Option<u64> {
    match rlimit::increase_nofile_limit(u64::MAX) {
        Ok(n) => Some(n),
        Err(e) => {
            tracing::warn!("cannot raise the open-file limit: {e}");
            None
        }
    }
}

/// Open connections per client address.
#[derive(Default)]
struct PerAddress(Mutex<HashMap<IpAddr, usize>>);

/// One connection counted against its address until dropped.
struct Claim {
    table: Arc<PerAddress>,
    ip: IpAddr,
}

impl PerAddress {
    fn claim(table: &Arc<PerAddress>, ip: IpAddr, max: usize) -> Option<Claim> {
        let mut map = table.0.lock().unwrap_or_else(|e| e.into_inner());
        let n = map.entry(ip).or_insert(0);
        if *n >= max {
            return None;
        }
        *n += 1;
        Some(Claim {
            table: table.clone(),
            ip,
        })
    }
}

impl Drop for Claim {
    fn drop(&mut self) {
        let mut map = self.table.0.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(n) = map.get_mut(&self.ip) {
            *n -= 1;
            if *n == 0 {
                map.remove(&self.ip);
            }
        }
    }
}

/// Serves `app` on `listener` until `stop` resolves; then stops accepting,
/// asks every connection to finish gracefully and waits for them. Refused
/// and timed-out connections are counted in `metrics`.
pub async fn serve(
    listener: TcpListener,
    app: Router,
    limits: ConnectionLimits,
    metrics: Arc<Metrics>,
    stop: impl Future<Output = ()>,
) -> std::io::Result<()> {
    let total = Arc::new(Semaphore::new(limits.max_connections.max(1)));
    let per_address = Arc::new(PerAddress::default());
    let (closing_tx, closing) = watch::channel(false);
    // Every connection task holds a sender; recv() is None once all ended.
    let (done_tx, mut done) = mpsc::channel::<()>(1);
    let mut stop = std::pin::pin!(stop);
    loop {
        let accepted = tokio::select! {
            a = listener.accept() => a,
            () = &mut stop => break,
        };
        let (tcp, remote) = match accepted {
            Ok(a) => a,
            Err(e) => {
                // Out of descriptors or similar: pause rather than spin.
                tracing::warn!("accept failed: {e}");
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        let Ok(permit) = total.clone().try_acquire_owned() else {
            tracing::debug!(%remote, "connection refused: --max-connections reached");
            metrics.refused_total_limit.fetch_add(1, Ordering::Relaxed);
            continue;
        };
        let Some(claim) = PerAddress::claim(&per_address, remote.ip(), limits.max_per_address)
        else {
            tracing::debug!(%remote, "connection refused: too many from this address");
            metrics.refused_per_address.fetch_add(1, Ordering::Relaxed);
            continue;
        };
        // No Nagle: a frame is followed at once by its small stats message,
        // which must not wait for the client's delayed ACK (~40 ms).
        if let Err(e) = tcp.set_nodelay(true) {
            tracing::debug!("TCP_NODELAY: {e}");
        }
        tokio::spawn(connection(
            tcp,
            app.clone(),
            limits.header_timeout,
            metrics.clone(),
            closing.clone(),
            (permit, claim, done_tx.clone()),
        ));
    }
    drop(done_tx);
    let _ = closing_tx.send(true);
    let _ = done.recv().await;
    Ok(())
}

/// One connection, until it ends or the server closes.
async fn connection(
    tcp: tokio::net::TcpStream,
    app: Router,
    header_timeout: Duration,
    metrics: Arc<Metrics>,
    mut closing: watch::Receiver<bool>,
    held: (OwnedSemaphorePermit, Claim, mpsc::Sender<()>),
) {
    let service = TowerToHyperService::new(app);
    let mut builder = hyper::server::conn::http1::Builder::new();
    builder
        .timer(TokioTimer::new())
        .header_read_timeout(header_timeout);
    let conn = builder
        .serve_connection(TokioIo::new(tcp), service)
        .with_upgrades();
    let mut conn = std::pin::pin!(conn);
    loop {
        tokio::select! {
            result = conn.as_mut() => {
                if let Err(e) = result {
                    if e.is_timeout() {
                        metrics.head_timeouts.fetch_add(1, Ordering::Relaxed);
                    }
                    tracing::trace!("connection ended: {e}");
                }
                break;
            }
            changed = closing.changed(), if !*closing.borrow() => {
                if changed.is_ok() {
                    conn.as_mut().graceful_shutdown();
                }
            }
        }
    }
    drop(held);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_address_holds_at_most_its_share_and_gets_it_back() {
        let table = Arc::new(PerAddress::default());
        let ip: IpAddr = "10.0.0.1".parse().expect("ip");
        let other: IpAddr = "10.0.0.2".parse().expect("ip");
        let a = PerAddress::claim(&table, ip, 2).expect("first");
        let _b = PerAddress::claim(&table, ip, 2).expect("second");
        assert!(
            PerAddress::claim(&table, ip, 2).is_none(),
            "a third is refused"
        );
        assert!(
            PerAddress::claim(&table, other, 2).is_some(),
            "another address is not"
        );
        drop(a);
        assert!(
            PerAddress::claim(&table, ip, 2).is_some(),
            "a closed one frees its place"
        );
    }
}
