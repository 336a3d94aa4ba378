//! A TCP relay that holds every chunk of data for a fixed time in each
//! direction: the round trip of a long link where the kernel has no
//! `tc netem` (`scripts/netem-bench.sh` puts it in the client's network
//! namespace, in front of a veth pair that `tbf` limits in rate). Order and
//! throughput are kept: data is queued with the time it may leave, so later
//! data does not wait behind the delay of earlier data.
//!
//! What it does not model: TCP itself sees short round trips on both hops
//! (no slow start or window limits from the delay), so it stands for a long
//! link with well-tuned TCP; the application's own round trips (a frame
//! out, its acknowledgement back) take the full delay.
//!
//!   cargo run --release --example delay_relay -- LISTEN UPSTREAM ONE_WAY_MS
//!   (e.g. 127.0.0.1:9090 10.77.0.1:8080 15 for a 30 ms round trip)

use std::net::SocketAddr;
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::tcp::{OwnedReadHalf, OwnedWriteHalf};
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::mpsc;
use tokio::time::Instant;

#[tokio::main]
async fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let parsed = match &args[..] {
        [listen, upstream, ms] => (listen.parse(), upstream.parse(), ms.parse::<u64>()),
        _ => {
            eprintln!("usage: delay_relay LISTEN UPSTREAM ONE_WAY_MS");
            std::process::exit(2);
        }
    };
    let (Ok(listen), Ok(upstream), Ok(ms)) = parsed else {
        eprintln!("delay_relay: LISTEN and UPSTREAM are HOST:PORT, ONE_WAY_MS a whole number");
        std::process::exit(2);
    };
    if let Err(e) = run(listen, upstream, Duration::from_millis(ms)).await {
        eprintln!("delay_relay: {e}");
        std::process::exit(1);
    }
}

async fn run(listen: SocketAddr, upstream: SocketAddr, delay: Duration) -> std::io::Result<()> {
    let listener = TcpListener::bind(listen).await?;
    println!(
        "relaying {listen} -> {upstream}, {} ms each way",
        delay.as_millis()
    );
    loop {
        let (down, _) = listener.accept().await?;
        tokio::spawn(async move {
            let Ok(up) = TcpStream::connect(upstream).await else {
                return;
            };
            let _ = (down.set_nodelay(true), up.set_nodelay(true));
            let ((down_r, down_w), (up_r, up_w)) = (down.into_split(), up.into_split());
            tokio::join!(pipe(down_r, up_w, delay), pipe(up_r, down_w, delay));
        });
    }
}

/// Copies `from` to `to`, each chunk leaving `delay` after it arrived.
async fn pipe(mut from: OwnedReadHalf, mut to: OwnedWriteHalf, delay: Duration) {
    let (tx, mut rx) = mpsc::unbounded_channel::<(Instant, Vec<u8>)>();
    let read = async move {
        let mut buf = vec![0u8; 64 * 1024];
        while let Ok(n @ 1..) = from.read(&mut buf).await {
            if tx
                .send((Instant::now() + delay, buf[..n].to_vec()))
                .is_err()
            {
                break;
            }
        }
    };
    let write = async move {
        while let Some((due, bytes)) = rx.recv().await {
            tokio::time::sleep_until(due).await;
            if to.write_all(&bytes).await.is_err() {
                break;
            }
        }
        let _ = to.shutdown().await;
    };
    tokio::join!(read, write);
}
