//! `pathstream-client`: drive a pathstream server from a shell.
//! Exit codes: 0 success, 2 bad arguments, 3 server error (message shown),
//! 4 server unreachable.

mod cli;
mod environment;
mod fanout;
mod focus;
mod guard;
mod quality;
mod scene;

use clap::Parser;
use cli::{vec3, Cli, Command, CreateArgs, RenderArgs};
use futures_util::StreamExt;
use guard::{create_guarded, owning, Interrupt};
use indicatif::{ProgressBar, ProgressStyle};
use pathstream_client::{
    CameraPatch, Client, ClientError, CreateSession, LightPatch, QualityPatch, SceneSpec,
    SessionStatus,
};
use quality::spp_summary;
use scene::{scene_spec, upload};
use std::path::Path;
use std::process::ExitCode;
use std::time::Duration;

/// A failure with its exit code.
struct Failure(u8, String);

impl From<ClientError> for Failure {
    fn from(e: ClientError) -> Self {
        let code = match e {
            ClientError::Server { .. } | ClientError::Protocol(_) => 3,
            ClientError::Unreachable(_) => 4,
            ClientError::Input(_) => 2,
        };
        Failure(code, e.to_string())
    }
}

/// `println!` for the command's output: `Ok` also when the reader has gone
/// (`pathstream-client sessions | head -1`), which `println!` answers with
/// a panic; any other failure to write fails the command.
macro_rules! outln {
    ($($arg:tt)*) => {
        $crate::write_out(format_args!("{}\n", format_args!($($arg)*)))
    };
}
pub(crate) use outln;

/// Writes `text` to standard output (see [`outln`]).
fn write_out(text: std::fmt::Arguments) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_fmt(text).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Failure(1, format!("writing to standard output: {e}")))
        }
        _ => Ok(()),
    }
}

fn usage(msg: String) -> Failure {
    Failure(2, msg)
}

fn extension(out: &Path) -> Result<&'static str, Failure> {
    match out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("png") => Ok("png"),
        Some("pfm") => Ok("pfm"),
        _ => Err(usage(format!(
            "{}: the output must end in .png or .pfm",
            out.display()
        ))),
    }
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), Failure> {
    std::fs::write(path, bytes)
        .map_err(|e| Failure(1, format!("cannot write {}: {e}", path.display())))
}

fn print_status(s: &SessionStatus) -> Result<(), Failure> {
    let text = serde_json::to_string_pretty(s).map_err(|e| Failure(1, e.to_string()))?;
    outln!("{text}")?;
    Ok(())
}

/// The session `args` ask `client` for (model files uploaded to it); with
/// `default_spp`, 64 spp when no halt is given.
async fn session_request(
    client: &Client,
    args: &CreateArgs,
    default_spp: bool,
) -> Result<CreateSession, Failure> {
    let mut quality = args.quality.patch();
    if default_spp && !args.quality.halts() {
        quality.spp = Some(Some(64));
    }
    let mut spec = scene_spec(client, &args.scene).await?;
    if let Some(map) = &args.environment {
        let id = upload(client, map, "--environment").await?;
        let SceneSpec::Json(json) = &mut spec else {
            return Err(usage(format!(
                "--environment: built-in scene '{}' is sent by name; give a scene JSON or model file",
                args.scene
            )));
        };
        json["environment"] = serde_json::json!({
            "map": id, "intensity": args.env_intensity, "rotation_deg": args.env_rotation
        });
    }
    Ok(CreateSession {
        scene: Some(spec),
        width: Some(args.width),
        height: Some(args.height),
        quality: Some(quality),
        backend: args.backend.clone(),
    })
}

async fn create(
    client: &Client,
    args: &CreateArgs,
    default_spp: bool,
) -> Result<SessionStatus, Failure> {
    let req = session_request(client, args, default_spp).await?;
    Ok(client.create_session(&req).await?)
}

async fn render(client: &Client, args: &RenderArgs) -> Result<(), Failure> {
    let kind = extension(&args.out)?;
    let mut interrupt = Interrupt::install()?;
    let session =
        create_guarded(client, &mut interrupt, create(client, &args.create, true)).await?;
    let id = session.id.clone();
    for w in &session.warnings {
        eprintln!("warning: {w}");
    }
    let work = async {
        let bar = ProgressBar::new(session.quality.spp.unwrap_or(0)).with_style(
            ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} spp  {msg}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        let status = loop {
            let s = client.session(&id).await?;
            bar.set_position(s.spp);
            let spread = if s.quality.adaptive {
                let p = s.spp_spread;
                format!("  min/med/max {}/{}/{} spp", p.min, p.median, p.max)
            } else {
                String::new()
            };
            bar.set_message(format!(
                "error {}  {:.2} M paths/s{spread}",
                s.error_estimate
                    .map_or("n/a".into(), |e| format!("{:.2}%", e * 100.0)),
                s.samples_per_sec / 1e6
            ));
            if s.halted() {
                break s;
            }
            tokio::time::sleep(Duration::from_millis(200)).await;
        };
        bar.finish_and_clear();
        if let Some(f) = &status.failure {
            return Err(Failure(3, format!("rendering failed on the server: {f}")));
        }
        let bytes = match kind {
            "png" => client.frame_png(&id, Some(status.spp), None).await?,
            _ => client.frame_pfm(&id, Some(status.spp), None).await?,
        };
        write(&args.out, &bytes)?;
        outln!(
            "{} {}x{}: {}, error estimate {}, {:.2} M paths/s on {} ({}) -> {}",
            status.scene,
            status.width,
            status.height,
            spp_summary(&status),
            status
                .error_estimate
                .map_or("n/a".into(), |e| format!("{:.2}%", e * 100.0)),
            status.samples_per_sec / 1e6,
            status.backend,
            status.device,
            args.out.display()
        )?;
        if status.devices.len() > 1 {
            for d in &status.devices {
                let failure = (d.failure.as_ref())
                    .map_or_else(String::new, |f| format!("; dropped out: {f}"));
                outln!(
                    "  {} ({}): {:.2} M paths/s, {} paths{failure}",
                    d.backend,
                    d.device,
                    d.samples_per_sec / 1e6,
                    d.samples
                )?;
            }
        }
        Ok(())
    };
    owning(client, &id, &mut interrupt, work).await
}

async fn orbit(
    client: &Client,
    scene: &str,
    center: Option<[f64; 3]>,
    frames: usize,
    spp: u64,
    size: (u32, u32),
    out_dir: &Path,
) -> Result<(), Failure> {
    if frames == 0 {
        return Err(usage("--frames: must be at least 1".into()));
    }
    std::fs::create_dir_all(out_dir)
        .map_err(|e| Failure(1, format!("{}: {e}", out_dir.display())))?;
    let req = CreateSession {
        scene: Some(scene_spec(client, scene).await?),
        width: Some(size.0),
        height: Some(size.1),
        quality: Some(QualityPatch {
            spp: Some(Some(spp)),
            ..QualityPatch::default()
        }),
        backend: None,
    };
    let mut interrupt = Interrupt::install()?;
    let session = create_guarded(client, &mut interrupt, async {
        Ok(client.create_session(&req).await?)
    })
    .await?;
    let id = session.id.clone();
    let work = async {
        let c = &session.camera;
        let (p, t, up) = (c.position, center.unwrap_or(c.look_at), c.up);
        // Rotate the position about the up axis through the look-at point
        // (Rodrigues' formula).
        let norm = (up[0] * up[0] + up[1] * up[1] + up[2] * up[2]).sqrt();
        let k = [up[0] / norm, up[1] / norm, up[2] / norm];
        let v = [p[0] - t[0], p[1] - t[1], p[2] - t[2]];
        let bar = ProgressBar::new(frames as u64);
        for i in 0..frames {
            let a = std::f64::consts::TAU * i as f64 / frames as f64;
            let (s, co) = a.sin_cos();
            let kxv = [
                k[1] * v[2] - k[2] * v[1],
                k[2] * v[0] - k[0] * v[2],
                k[0] * v[1] - k[1] * v[0],
            ];
            let kdv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
            let r: [f64; 3] =
                std::array::from_fn(|j| v[j] * co + kxv[j] * s + k[j] * kdv * (1.0 - co));
            let position = [t[0] + r[0], t[1] + r[1], t[2] + r[2]];
            client
                .set_camera(
                    &id,
                    &CameraPatch {
                        position: Some(position),
                        look_at: Some(t),
                        ..CameraPatch::default()
                    },
                )
                .await?;
            let png = client
                .frame_png(&id, Some(spp), Some(Duration::from_secs(600)))
                .await?;
            write(&out_dir.join(format!("frame_{i:04}.png")), &png)?;
            bar.inc(1);
        }
        bar.finish_and_clear();
        outln!("{frames} frames of {scene} in {}", out_dir.display())?;
        Ok(())
    };
    owning(client, &id, &mut interrupt, work).await
}

/// The servers `--server` (or `PATHSTREAM_URL`) names: every value, split
/// at commas.
fn servers(values: &[String], token: Option<&String>) -> Result<Vec<Client>, Failure> {
    let urls: Vec<&str> = values
        .iter()
        .flat_map(|v| v.split(','))
        .map(str::trim)
        .filter(|u| !u.is_empty())
        .collect();
    if urls.is_empty() {
        return Err(usage("--server: no server URL given".into()));
    }
    urls.into_iter()
        .map(|u| Ok(Client::new(u)?.token(token.cloned())))
        .collect()
}

async fn run(cli: Cli) -> Result<(), Failure> {
    let client = match <[Client; 1]>::try_from(servers(&cli.server, cli.token.as_ref())?) {
        Ok([client]) => client,
        Err(clients) => {
            return match &cli.command {
                Command::Render(args) => fanout::render(clients, args).await,
                _ => Err(usage(
                    "several servers (--server given more than once, or a comma in \
                     PATHSTREAM_URL) are for `render` only"
                        .into(),
                )),
            }
        }
    };
    match cli.command {
        Command::Render(args) => render(&client, &args).await,
        Command::Sessions => {
            for s in client.sessions().await? {
                outln!(
                    "{}  {} {}x{}  {} spp  {}  {}",
                    s.id,
                    s.scene,
                    s.width,
                    s.height,
                    s.spp,
                    s.state,
                    s.backend
                )?;
            }
            Ok(())
        }
        Command::Create(args) => print_status(&create(&client, &args, false).await?),
        Command::Status { id } => print_status(&client.session(&id).await?),
        Command::Focus(a) => focus::focus(&client, &a).await,
        Command::Environment(a) => environment::set(&client, &a).await,
        Command::Camera(a) => print_status(
            &client
                .set_camera(
                    &a.id,
                    &CameraPatch {
                        position: a.position,
                        look_at: a.look_at,
                        up: a.up,
                        vfov_deg: a.vfov_deg,
                        near_clip: None,
                        aperture: a.aperture,
                        f_number: a.f_number,
                        focus_distance: a.focus_distance,
                        projection: a.projection,
                        ortho_height: a.ortho_height,
                    },
                )
                .await?,
        ),
        Command::Light(a) => print_status(
            &client
                .set_light(
                    &a.id,
                    &LightPatch {
                        position: a.position,
                        color: a.color,
                        intensity: a.intensity,
                    },
                )
                .await?,
        ),
        Command::Quality { id, quality } => {
            print_status(&client.set_quality(&id, &quality.patch()).await?)
        }
        Command::Frame {
            id,
            min_spp,
            denoise,
            raw,
            out,
        } => {
            let asked = (denoise || raw).then_some(denoise);
            let kind = extension(&out)?;
            write(&out, &client.frame_as(&id, kind, min_spp, asked).await?)
        }
        Command::Delete { id } => Ok(client.delete_session(&id).await?),
        Command::Upload { file } => {
            outln!(
                "{}",
                upload(&client, &file, &file.display().to_string()).await?
            )?;
            Ok(())
        }
        Command::Assets => {
            let list = client.assets().await?;
            for a in &list.assets {
                outln!(
                    "{}  {}  {}  {} triangles  {} bytes",
                    a.id,
                    a.name,
                    a.format,
                    a.triangles,
                    a.memory_bytes
                )?;
            }
            Ok(())
        }
        Command::DeleteAsset { id } => Ok(client.delete_asset(&id).await?),
        Command::Stream {
            id,
            frames,
            out_dir,
        } => {
            std::fs::create_dir_all(&out_dir)
                .map_err(|e| Failure(1, format!("{}: {e}", out_dir.display())))?;
            let mut stream = client.stream(&id).await?;
            let mut saved = 0;
            while saved < frames {
                match stream.next().await {
                    Some(Ok(frame)) => {
                        write(&out_dir.join(format!("frame_{saved:04}.png")), &frame.png)?;
                        outln!("frame {saved}: {} spp", frame.status.spp)?;
                        saved += 1;
                    }
                    Some(Err(e)) => return Err(e.into()),
                    None => {
                        return Err(Failure(3, format!("the stream ended after {saved} frames")))
                    }
                }
            }
            Ok(())
        }
        Command::Orbit {
            scene,
            center,
            frames,
            spp,
            width,
            height,
            out_dir,
        } => {
            orbit(
                &client,
                &scene,
                center,
                frames,
                spp,
                (width, height),
                &out_dir,
            )
            .await
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let runtime = match tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
    {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: {e}");
            return ExitCode::from(1);
        }
    };
    match runtime.block_on(run(cli)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure(code, message)) => {
            eprintln!("error: {message}");
            ExitCode::from(code)
        }
    }
}
