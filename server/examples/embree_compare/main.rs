//! pathstream's CPU traversal next to Embree 3, on the same mesh and the
//! same rays, in one run (the meshes issue's "within 2x of Embree").
//!
//! ```text
//! apt-get install -y libembree-dev        # Debian 12: Embree 3.13.5
//! cargo run --release -p pathstream --features embree --example embree_compare -- \
//!     [TRIANGLES...] [--out FILE.csv] [--repeats N] [--quality] [--verbose]
//! ```
//!
//! For each size (default 10k, 100k, 1M, 4M triangles) `bench::meshes`
//! makes the bumpy sphere, its pathstream scene and world, 512x512 camera
//! rays and one diffuse bounce per camera hit. Embree gets the mesh's own
//! f32 vertices and indices (object space, as pathstream's BVH holds them)
//! and every ray mapped into object space by the instance's
//! `obj_from_cam`, exactly as pathstream maps it before its traversal (the
//! map is done inside Embree's timed loop too). So both trace the same
//! f32 triangles with the same f32 rays; the agreement check compares hit
//! or miss, triangle and distance of every ray.
//!
//! Embree traces single rays (`rtcIntersect1`) on rayon's threads (the
//! same pool as pathstream), tnear = 0 for every ray: camera rays start at
//! the camera; bounce rays start where pathstream spawned them, already
//! moved off the surface by its error bound (pathstream also skips the
//! triangle a ray leaves; Embree cannot, and self-hits are counted). Rays
//! per second are the best of `--repeats` passes (default 3), the tracers
//! taking turns pass by pass, so that load from elsewhere hits all alike.
//! "Embree robust" is `RTC_SCENE_FLAG_ROBUST` (watertight, like
//! pathstream's test). `--quality` adds Embree with `RTC_BUILD_QUALITY_HIGH`
//! (the default is MEDIUM). `--verbose` turns on Embree's own report
//! (`verbose=3`: its ISA, the BVH it builds, the intersectors it picks).
//! `--packets` adds Embree tracing the same rays in packets of sixteen
//! neighbouring rays (`rtcIntersect16`, as a wavefront of sixteen lanes
//! would hand them over), default build, checked to give the single
//! rays' hits.
//! `--first-rays` measures `cornell-mesh`'s first rays instead, a pixel's
//! sixteen samples to a packet (`first_rays.rs`).
//!
//! Embree is bound by the small `extern "C"` block in `embree.rs` (Embree 3's C API,
//! `libembree3`); only this example uses it, behind the `embree` feature.

use pathstream::bench::meshes::{ray_set, rays_per_sec, RaySet};
use pathstream::model::generate::bumpy_sphere;
use pathstream::render::backend::nearest_hits;
use pathstream::render::ray::Ray;
use pathstream::render::shape::Mesh;
use pathstream::render::world::{Hit, Origin};
use std::fmt::Write as _;
use std::time::Instant;

mod embree;
mod first_rays;

use embree::{ffi, Device, EmbreeScene, Query};

/// How far Embree's hits agree with pathstream's on one ray kind.
#[derive(Debug, Default)]
struct Agreement {
    rays: usize,
    hits_pathstream: usize,
    hits_embree: usize,
    /// One hit, the other missed.
    hit_miss: usize,
    same_triangle: usize,
    /// Both hit, different triangles (ties on shared edges, or a different
    /// surface).
    other_triangle: usize,
    /// Of those, where the distances differ by more than 1e-4 relative.
    other_surface: usize,
    /// Largest |t_embree - t_pathstream| / t_pathstream where both hit the
    /// same triangle.
    max_rel_dt: f64,
    /// Embree hits on the triangle the ray leaves (pathstream skips it).
    self_hits: usize,
}

impl Agreement {
    fn of(rays: &[(Ray, Origin)], ours: &[Option<Hit>], theirs: &[Option<Hit>]) -> Agreement {
        let mut a = Agreement {
            rays: rays.len(),
            ..Agreement::default()
        };
        for (((_, from), p), e) in rays.iter().zip(ours).zip(theirs) {
            a.hits_pathstream += usize::from(p.is_some());
            a.hits_embree += usize::from(e.is_some());
            if let Some(e) = e {
                a.self_hits += usize::from(e.prim == from.prim);
            }
            match (p, e) {
                (Some(p), Some(e)) => {
                    let rel = f64::from((e.t - p.t).abs()) / f64::from(p.t);
                    if e.prim == p.prim {
                        a.same_triangle += 1;
                        a.max_rel_dt = a.max_rel_dt.max(rel);
                    } else {
                        a.other_triangle += 1;
                        a.other_surface += usize::from(rel > 1e-4);
                    }
                }
                (None, None) => {}
                _ => a.hit_miss += 1,
            }
        }
        a
    }

    fn summary(&self) -> String {
        format!(
            "{} rays: hits {} (pathstream) / {} (Embree), hit-vs-miss {}, same triangle {} ({:.4}%), other triangle {} (of which {} at a distance >1e-4 rel. off), max rel. |dt| on the same triangle {:.2e}, Embree self-hits {}",
            self.rays,
            self.hits_pathstream,
            self.hits_embree,
            self.hit_miss,
            self.same_triangle,
            100.0 * self.same_triangle as f64 / self.hits_pathstream.max(1) as f64,
            self.other_triangle,
            self.other_surface,
            self.max_rel_dt,
            self.self_hits,
        )
    }
}

/// One size's results.
struct Row {
    triangles: usize,
    build_scene: f64,
    build_mesh: f64,
    build_embree: f64,
    build_robust: f64,
    build_high: Option<f64>,
    /// Rays/s: [pathstream, Embree, Embree robust, Embree high quality].
    camera: [f64; 4],
    bounce: [f64; 4],
    camera_rays: usize,
    bounce_rays: usize,
    /// Share of the machine's CPU time that other processes took while the
    /// passes were timed (from /proc; None where it cannot be read).
    others: Option<f64>,
    agree_camera: Agreement,
    agree_bounce: Agreement,
    agree_camera_robust: Agreement,
    agree_bounce_robust: Agreement,
    /// With `--packets`: Embree's rays/s in packets of sixteen (camera,
    /// bounce), and how many rays' hits differ from its single rays'.
    packets: Option<([f64; 2], usize)>,
}

struct Args {
    sizes: Vec<usize>,
    out: Option<String>,
    repeats: u32,
    quality: bool,
    verbose: bool,
    packets: bool,
    first_rays: bool,
}

fn parse_args() -> Args {
    let mut args = Args {
        sizes: Vec::new(),
        out: None,
        repeats: 3,
        quality: false,
        verbose: false,
        packets: false,
        first_rays: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--out" => args.out = Some(it.next().expect("--out FILE")),
            "--repeats" => {
                args.repeats = it.next().and_then(|n| n.parse().ok()).expect("--repeats N")
            }
            "--quality" => args.quality = true,
            "--verbose" => args.verbose = true,
            "--packets" => args.packets = true,
            "--first-rays" => args.first_rays = true,
            "-h" | "--help" => {
                println!("embree_compare [TRIANGLES...] [--out FILE.csv] [--repeats N] [--quality] [--verbose] [--packets] [--first-rays]");
                std::process::exit(0);
            }
            n => args
                .sizes
                .push(parse_size(n).unwrap_or_else(|| panic!("not a size or an option: {n}"))),
        }
    }
    if args.sizes.is_empty() {
        args.sizes = vec![10_000, 100_000, 1_000_000, 4_000_000];
    }
    args
}

/// "4000000", "4M", "100k".
fn parse_size(s: &str) -> Option<usize> {
    let (digits, scale) = match s.chars().last()? {
        'k' | 'K' => (&s[..s.len() - 1], 1_000.0),
        'm' | 'M' => (&s[..s.len() - 1], 1_000_000.0),
        _ => (s, 1.0),
    };
    digits.parse::<f64>().ok().map(|x| (x * scale) as usize)
}

fn measure(device: &Device, n: usize, args: &Args) -> Row {
    let RaySet {
        scene,
        world,
        camera,
        bounce,
        build_seconds,
    } = ray_set(n);
    let mesh = &scene.imports[0].instances[0];
    assert_eq!(
        mesh.world_from_object,
        pathstream::render::math::DAffine3::IDENTITY
    );
    assert_eq!((world.objects.len(), world.instances.len()), (1, 1));
    let map = world.instances[0].obj_from_cam;
    let (positions, triangles) = (&mesh.mesh.positions, &mesh.mesh.triangles);

    // pathstream's BVH build alone (the scene's build also converts and
    // checks the JSON mesh data).
    let data = bumpy_sphere(n);
    let start = Instant::now();
    let again = Mesh::new(data).expect("a valid mesh");
    let build_mesh = start.elapsed().as_secs_f64();
    assert_eq!(again.triangles.len(), triangles.len());
    drop(again);

    let medium = EmbreeScene::build(
        device,
        positions,
        triangles,
        ffi::RTC_SCENE_FLAG_NONE,
        ffi::RTC_BUILD_QUALITY_MEDIUM,
    );
    let robust = EmbreeScene::build(
        device,
        positions,
        triangles,
        ffi::RTC_SCENE_FLAG_ROBUST,
        ffi::RTC_BUILD_QUALITY_MEDIUM,
    );
    let high = args.quality.then(|| {
        EmbreeScene::build(
            device,
            positions,
            triangles,
            ffi::RTC_SCENE_FLAG_NONE,
            ffi::RTC_BUILD_QUALITY_HIGH,
        )
    });

    // Agreement: every ray, both kinds.
    let ours_camera = nearest_hits(&world, &camera);
    let ours_bounce = nearest_hits(&world, &bounce);
    let agree_camera = Agreement::of(&camera, &ours_camera, &medium.hits(&map, &camera));
    let agree_bounce = Agreement::of(&bounce, &ours_bounce, &medium.hits(&map, &bounce));
    let agree_camera_robust = Agreement::of(&camera, &ours_camera, &robust.hits(&map, &camera));
    let agree_bounce_robust = Agreement::of(&bounce, &ours_bounce, &robust.hits(&map, &bounce));
    drop((ours_camera, ours_bounce));

    // Speed: the tracers take turns, pass by pass; best pass of each.
    let differ = |a: &[Option<Hit>], b: &[Option<Hit>]| {
        a.iter()
            .zip(b)
            .filter(|(a, b)| a.map(|h| (h.prim, h.t)) != b.map(|h| (h.prim, h.t)))
            .count()
    };
    let packets_differ = args.packets.then(|| {
        differ(
            &medium.hits(&map, &camera),
            &medium.hits16(&map, &camera, false),
        ) + differ(
            &medium.hits(&map, &bounce),
            &medium.hits16(&map, &bounce, false),
        )
    });
    let time = |rays: &[(Ray, Origin)]| {
        let mut best = [0.0f64; 5];
        for _ in 0..args.repeats.max(1) {
            let mut pass = [
                rays_per_sec(&world, rays, 1),
                medium.rays_per_sec(&map, rays, Query::Single),
                robust.rays_per_sec(&map, rays, Query::Single),
                high.as_ref()
                    .map_or(0.0, |h| h.rays_per_sec(&map, rays, Query::Single)),
                if args.packets {
                    medium.rays_per_sec(&map, rays, Query::Packets)
                } else {
                    0.0
                },
            ];
            for (b, p) in best.iter_mut().zip(&mut pass) {
                *b = b.max(*p);
            }
        }
        best
    };
    let before = CpuTicks::now();
    let camera_speed = time(&camera);
    let bounce_speed = time(&bounce);
    let others = CpuTicks::now()
        .zip(before)
        .map(|(after, before)| after.others_share(&before));
    let packets = packets_differ.map(|d| ([camera_speed[4], bounce_speed[4]], d));
    let (camera_speed, bounce_speed) = (
        [
            camera_speed[0],
            camera_speed[1],
            camera_speed[2],
            camera_speed[3],
        ],
        [
            bounce_speed[0],
            bounce_speed[1],
            bounce_speed[2],
            bounce_speed[3],
        ],
    );
    Row {
        packets,
        triangles: triangles.len(),
        build_scene: build_seconds,
        build_mesh,
        build_embree: medium.build_seconds,
        build_robust: robust.build_seconds,
        build_high: high.as_ref().map(|h| h.build_seconds),
        camera: camera_speed,
        bounce: bounce_speed,
        camera_rays: camera.len(),
        bounce_rays: bounce.len(),
        others,
        agree_camera,
        agree_bounce,
        agree_camera_robust,
        agree_bounce_robust,
    }
}

/// CPU time so far (Linux clock ticks): the machine's in all and idle,
/// and this process's.
#[derive(Clone, Copy)]
struct CpuTicks {
    total: u64,
    idle: u64,
    ours: u64,
}

impl CpuTicks {
    fn now() -> Option<CpuTicks> {
        let stat = std::fs::read_to_string("/proc/stat").ok()?;
        let cpu: Vec<u64> = stat
            .lines()
            .next()?
            .split_whitespace()
            .skip(1)
            .map_while(|x| x.parse().ok())
            .collect();
        // user nice system idle iowait irq softirq steal (guest time is
        // already in user).
        let total = cpu.iter().take(8).sum();
        let idle = cpu.get(3)? + cpu.get(4)?;
        let own = std::fs::read_to_string("/proc/self/stat").ok()?;
        let fields: Vec<&str> = own.rsplit_once(')')?.1.split_whitespace().collect();
        // utime and stime: fields 14 and 15 of the line, 12 and 13 after
        // the command name.
        let ours = fields.get(11)?.parse::<u64>().ok()? + fields.get(12)?.parse::<u64>().ok()?;
        Some(CpuTicks { total, idle, ours })
    }

    /// Share of all CPU time since `before` that neither idled nor was ours.
    fn others_share(&self, before: &CpuTicks) -> f64 {
        let total = self.total.saturating_sub(before.total).max(1) as f64;
        let busy = self
            .total
            .saturating_sub(before.total)
            .saturating_sub(self.idle.saturating_sub(before.idle));
        busy.saturating_sub(self.ours.saturating_sub(before.ours)) as f64 / total
    }
}

fn mrays(x: f64) -> String {
    format!("{:.2}", x / 1e6)
}

fn table(rows: &[Row], quality: bool) -> String {
    let mut s = String::new();
    s.push_str("| triangles | build s: pathstream scene / mesh BVH | build s: Embree / robust | camera Mrays/s: pathstream | Embree | Embree robust | ratio Embree/ps (robust/ps) | bounce Mrays/s: pathstream | Embree | Embree robust | ratio Embree/ps (robust/ps) |\n");
    s.push_str("| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    for r in rows {
        let ratio = |x: &[f64; 4]| format!("{:.2} ({:.2})", x[1] / x[0], x[2] / x[0]);
        let _ = writeln!(
            s,
            "| {} | {:.3} / {:.3} | {:.3} / {:.3} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.triangles,
            r.build_scene,
            r.build_mesh,
            r.build_embree,
            r.build_robust,
            mrays(r.camera[0]),
            mrays(r.camera[1]),
            mrays(r.camera[2]),
            ratio(&r.camera),
            mrays(r.bounce[0]),
            mrays(r.bounce[1]),
            mrays(r.bounce[2]),
            ratio(&r.bounce),
        );
    }
    if rows.iter().any(|r| r.packets.is_some()) {
        s.push_str("\nEmbree single rays (rtcIntersect1) vs packets of 16 (rtcIntersect16), default build:\n\n");
        s.push_str("| triangles | camera Mrays/s: single / packets | bounce Mrays/s: single / packets | rays whose hit differs |\n");
        s.push_str("| ---: | ---: | ---: | ---: |\n");
        for r in rows {
            let Some(([camera, bounce], differ)) = r.packets else {
                continue;
            };
            let _ = writeln!(
                s,
                "| {} | {} / {} | {} / {} | {} |",
                r.triangles,
                mrays(r.camera[1]),
                mrays(camera),
                mrays(r.bounce[1]),
                mrays(bounce),
                differ,
            );
        }
    }
    if quality {
        s.push_str("\nEmbree build quality MEDIUM (default) vs HIGH:\n\n");
        s.push_str("| triangles | build s: MEDIUM / HIGH | camera Mrays/s: MEDIUM / HIGH | bounce Mrays/s: MEDIUM / HIGH |\n");
        s.push_str("| ---: | ---: | ---: | ---: |\n");
        for r in rows {
            let _ = writeln!(
                s,
                "| {} | {:.3} / {:.3} | {} / {} | {} / {} |",
                r.triangles,
                r.build_embree,
                r.build_high.unwrap_or(f64::NAN),
                mrays(r.camera[1]),
                mrays(r.camera[3]),
                mrays(r.bounce[1]),
                mrays(r.bounce[3]),
            );
        }
    }
    s
}

fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "triangles,camera_rays,bounce_rays,build_s_pathstream_scene,build_s_pathstream_mesh,build_s_embree,build_s_embree_robust,build_s_embree_high,\
camera_rays_per_s_pathstream,camera_rays_per_s_embree,camera_rays_per_s_embree_robust,camera_rays_per_s_embree_high,\
bounce_rays_per_s_pathstream,bounce_rays_per_s_embree,bounce_rays_per_s_embree_robust,bounce_rays_per_s_embree_high,\
camera_hit_miss,camera_other_triangle,bounce_hit_miss,bounce_other_triangle,bounce_embree_self_hits,others_cpu_share\n",
    );
    for r in rows {
        let opt = |x: Option<f64>| x.map_or(String::new(), |x| format!("{x:.6}"));
        let rate = |x: f64| {
            if x > 0.0 {
                format!("{x:.0}")
            } else {
                String::new()
            }
        };
        let _ = writeln!(
            s,
            "{},{},{},{:.6},{:.6},{:.6},{:.6},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.triangles,
            r.camera_rays,
            r.bounce_rays,
            r.build_scene,
            r.build_mesh,
            r.build_embree,
            r.build_robust,
            opt(r.build_high),
            rate(r.camera[0]),
            rate(r.camera[1]),
            rate(r.camera[2]),
            rate(r.camera[3]),
            rate(r.bounce[0]),
            rate(r.bounce[1]),
            rate(r.bounce[2]),
            rate(r.bounce[3]),
            r.agree_camera.hit_miss,
            r.agree_camera.other_triangle,
            r.agree_bounce.hit_miss,
            r.agree_bounce.other_triangle,
            r.agree_bounce.self_hits,
            r.others.map_or(String::new(), |x| format!("{x:.3}")),
        );
    }
    s
}

fn main() {
    let args = parse_args();
    let threads = rayon::current_num_threads();
    let mut config = format!("threads={threads}");
    if args.verbose {
        config.push_str(",verbose=3");
    }
    let device = Device::new(&config);
    let v = device.version();
    eprintln!(
        "Embree {}.{}.{} (device \"{config}\"), rayon threads {threads}, best of {} passes",
        v / 10000,
        v / 100 % 100,
        v % 100,
        args.repeats
    );
    if args.first_rays {
        first_rays::run(&device, args.repeats);
        return;
    }
    let mut rows = Vec::new();
    for &n in &args.sizes {
        eprintln!("{n} triangles ...");
        let row = measure(&device, n, &args);
        eprintln!("  camera, Embree:        {}", row.agree_camera.summary());
        eprintln!(
            "  camera, Embree robust: {}",
            row.agree_camera_robust.summary()
        );
        eprintln!("  bounce, Embree:        {}", row.agree_bounce.summary());
        eprintln!(
            "  bounce, Embree robust: {}",
            row.agree_bounce_robust.summary()
        );
        if let Some(others) = row.others {
            eprintln!("  other processes took {:.0}% of the machine's CPU time while the passes were timed", 100.0 * others);
        }
        rows.push(row);
    }
    println!("{}", table(&rows, args.quality));
    if let Some(out) = &args.out {
        std::fs::write(out, csv(&rows)).unwrap_or_else(|e| panic!("writing {out}: {e}"));
        eprintln!("wrote {out}");
    }
}
