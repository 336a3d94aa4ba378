//! Sessions this command creates are deleted whatever happens, Ctrl-C
//! included (exit code 130).

use super::Failure;
use pathstream_client::{Client, SessionStatus};
use std::time::Duration;

/// Ctrl-C, caught from the moment this is made (before the session it
/// guards is created): a Ctrl-C no longer ends the process on the spot, and
/// one that comes before anyone waits for it is kept, not lost.
pub struct Interrupt {
    #[cfg(unix)]
    signal: tokio::signal::unix::Signal,
    #[cfg(windows)]
    signal: tokio::signal::windows::CtrlC,
}

impl Interrupt {
    pub fn install() -> Result<Self, Failure> {
        #[cfg(unix)]
        let signal = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::interrupt());
        #[cfg(windows)]
        let signal = tokio::signal::windows::ctrl_c();
        let signal = signal.map_err(|e| Failure(1, format!("cannot catch Ctrl-C: {e}")))?;
        Ok(Self { signal })
    }

    pub async fn received(&mut self) {
        self.signal.recv().await;
    }
}

/// How long a Ctrl-C during session creation waits for the server's answer,
/// so that the session it made can be deleted.
pub const CREATE_GRACE: Duration = Duration::from_secs(10);

/// Creates a session under `interrupt`: on a Ctrl-C while the request is out,
/// waits (briefly) for the session the server may have made, deletes it, and
/// fails with exit code 130.
pub async fn create_guarded<F>(
    client: &Client,
    interrupt: &mut Interrupt,
    create: F,
) -> Result<SessionStatus, Failure>
where
    F: std::future::Future<Output = Result<SessionStatus, Failure>>,
{
    let mut create = std::pin::pin!(create);
    tokio::select! {
        biased;
        created = &mut create => return created,
        () = interrupt.received() => {}
    }
    if let Ok(Ok(session)) = tokio::time::timeout(CREATE_GRACE, create).await {
        let _ = client.delete_session(&session.id).await;
    }
    Err(Failure(130, "interrupted".into()))
}

/// Runs `work` for a session this command created, then deletes the session
/// whatever happened, Ctrl-C included (exit code 130).
pub async fn owning<F>(
    client: &Client,
    id: &str,
    interrupt: &mut Interrupt,
    work: F,
) -> Result<(), Failure>
where
    F: std::future::Future<Output = Result<(), Failure>>,
{
    let result = tokio::select! {
        biased;
        () = interrupt.received() => Err(Failure(130, "interrupted".into())),
        r = work => r,
    };
    let deleted = client.delete_session(id).await;
    result?;
    deleted?;
    Ok(())
}
