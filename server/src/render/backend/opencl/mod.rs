//! The OpenCL backend: the kernel in `kernels/`, specialised per scene,
//! run on any OpenCL 1.2 device. The library is loaded at run time
//! (`opencl3`'s `dynamic` feature), so the binary runs where there is none.
//!
//! The device keeps the scene, the parameters and the film between launches;
//! a launch adds samples to every pixel in index order with compensated f32
//! sums (see `kernels/render.cl`), and after each `render` call the film comes
//! back once and replaces the host's sums. If anything fails the host film is
//! left as it was: no accumulated sample is lost.
//!
//! `unsafe` is allowed statement by statement, each with a `SAFETY:` comment:
//! opencl3 leaves to its caller that host pointers outlive the device's use
//! of them (every transfer here blocks), that buffers are as large as what
//! kernels touch, and that kernel arguments have the kernel's types. Only
//! `bytemuck::Pod` types cross between host and device memory, so any bytes
//! either side writes are valid values on the other.

mod buffers;
mod check;
#[cfg(test)]
mod contract_tests;
mod devices;
mod guides;
mod launch;
mod layout;
mod meshes;
mod program;
mod slice;
mod staging;
mod textures;
mod tiles;

pub use tiles::TileDispatch;

pub use buffers::MemoryLimits;
pub use check::{CheckArg, Checks};
pub use devices::{auto_pick, list as list_devices, DeviceInfo};
pub use layout::{
    device_uses_bvh, pack, shared_defines, Material as KernelMaterial, Object as KernelObject,
    Packed, Params as KernelParams, SHARED_CONSTANTS,
};
pub use program::{common_options, Features, ProgramKey, SOURCES};

use crate::render::film::Film;
use crate::render::job::RenderJob;
use bytemuck::Pod;
use opencl3::command_queue::CommandQueue;
use opencl3::context::Context;
use opencl3::kernel::Kernel;
use opencl3::memory::{Buffer, CL_MEM_READ_ONLY, CL_MEM_READ_WRITE};
use opencl3::program::Program;
use opencl3::types::{cl_mem_flags, CL_BLOCKING};
use staging::Staging;
use std::collections::HashMap;
use std::ptr;
use std::time::{Duration, Instant};

/// A launch should return within about this long, so updates feel immediate.
pub const LAUNCH_TARGET: Duration = Duration::from_millis(30);
/// The same on a GPU: a pass gives up for a change between launches, and a
/// GPU's launch costs microseconds, so its launches are shorter (a change
/// waits for less; docs/BENCHMARKS.md, *The server on the GPU*).
pub const GPU_LAUNCH_TARGET: Duration = Duration::from_millis(8);
/// Most job states kept on the device at once (one per recent session).
const RESIDENT_JOBS: usize = 16;
/// Most device memory their films may take together.
const RESIDENT_FILM_BYTES: usize = 1 << 30;
/// Most pixels one launch covers on a CPU device; larger images take
/// several launches (PoCL compiles a kernel anew for each launch size, and
/// a CPU's few cores are full long before this).
pub const TILE: usize = 1 << 16;
/// Most pixels one launch covers on a GPU: a 65,536-item launch fills a
/// quarter of an H100 (132 SMs x 2,048 resident work-items), so a GPU takes
/// images up to 4 Mpixel (1920x1080 and more) in one launch.
pub const GPU_TILE: usize = 1 << 22;
/// Work-items per work-group (a multiple of NVIDIA's warp and AMD's
/// wavefront, and small enough for any device's limit).
const LOCAL_SIZE: usize = 64;
/// Floats per pixel in the device film: [even hi, even lo, odd hi, odd lo] x
/// rgb, the odd samples' from `FILM_FLOATS / 2` (a shared constant: the
/// kernel's stride and offset are this one).
const FILM_FLOATS: usize = 12;

/// A positive whole number from the environment variable `name`, if set.
fn env_usize(name: &str) -> Option<usize> {
    let v = std::env::var(name).ok()?;
    match v.trim().parse::<usize>() {
        Ok(n) if n > 0 => Some(n),
        _ => {
            tracing::warn!("{name}={v:?} is not a positive whole number: ignored");
            None
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum OpenClError {
    #[error("no OpenCL device: {0}")]
    Unavailable(String),
    #[error("OpenCL program failed to build for {device}: {log}")]
    Build { device: String, log: String },
    #[error("OpenCL {what} failed: {code}")]
    Call { what: &'static str, code: String },
    /// The scene uses what the kernel does not model yet.
    #[error("the OpenCL backend cannot render this scene: {0}")]
    Unsupported(String),
}

/// Why the kernel cannot render `job`'s scene on `device`, if it cannot:
/// meshes need double precision (the watertight triangle test's exact
/// fallback), which NVIDIA's and PoCL's devices have.
pub fn unsupported(job: &RenderJob, device: &DeviceInfo) -> Option<String> {
    (!job.world.instances.is_empty() && !device.fp64).then(|| {
        format!(
            "it has triangle meshes, and {} has no double precision (cl_khr_fp64)",
            device.name.trim()
        )
    })
}

/// How kernels use a device buffer. Neither variant lets OpenCL use or copy
/// host memory (`CL_MEM_USE_HOST_PTR`, `CL_MEM_COPY_HOST_PTR`), which is what
/// makes creating a buffer with a null host pointer sound.
#[derive(Clone, Copy, Debug)]
enum Access {
    ReadOnly,
    ReadWrite,
}

impl Access {
    fn flags(self) -> cl_mem_flags {
        match self {
            Access::ReadOnly => CL_MEM_READ_ONLY,
            Access::ReadWrite => CL_MEM_READ_WRITE,
        }
    }
}

fn call(what: &'static str) -> impl Fn(opencl3::error_codes::ClError) -> OpenClError {
    move |e| OpenClError::Call {
        what,
        code: e.to_string(),
    }
}

/// Device buffers for the job in flight.
struct JobState {
    job_id: u64,
    key: ProgramKey,
    scene: buffers::SceneBuffers,
    film: Buffer<f32>,
    /// The denoiser's feature sums, GUIDE_FLOATS per pixel (one float
    /// where the job keeps none: see `guides.rs`).
    guides: Buffer<f32>,
    guided: bool,
    rejected: Buffer<u32>,
    pixels: usize,
    /// The index of the device film's first sample (see [`Film::block`]).
    first: u64,
    /// Samples per pixel the device film holds.
    spp: u64,
    /// Pixels `0..next` hold sample `spp` too (a slice in progress).
    next: usize,
    /// Camera paths the device film holds (adaptive tiles included).
    samples: u64,
    /// Adaptive work entries for the next launches (see `tiles.rs`).
    work: Buffer<[u32; 4]>,
    /// Entries `work` has room for.
    work_capacity: usize,
    /// Measured launch time per sample per pixel.
    per_sample: Option<Duration>,
    /// Rejections the device counter held at the last read-back.
    rejected_reported: u64,
    /// Device memory its buffers take.
    bytes: usize,
}

pub struct OpenClBackend {
    info: DeviceInfo,
    context: Context,
    queue: CommandQueue,
    programs: HashMap<ProgramKey, (Program, Kernel)>,
    /// Device state of recent jobs, most recently used last: a server worker
    /// round-robins its sessions, and each keeps its film on the device.
    states: Vec<JobState>,
    /// Use the one generic program instead of specialised ones (benchmark).
    pub generic: bool,
    /// Test hook: make every n-th sample NaN.
    pub inject_nan_every: Option<u64>,
    /// Test hook: fail every launch from now on, as a lost device would.
    pub fail_launches: bool,
    /// Test hook: set `fail_launches` after this many more launches.
    pub fail_after_launches: Option<u64>,
    /// How long one launch should take ([`LAUNCH_TARGET`], on GPUs
    /// [`GPU_LAUNCH_TARGET`]).
    pub launch_target: Duration,
    /// How long the last upload of a job's scene and film took, and the
    /// device memory they take.
    pub last_upload: Option<(Duration, usize)>,
    /// Bytes of scene arrays uploaded so far (a map or textures shared
    /// across jobs count once).
    pub scene_bytes_uploaded: u64,
    /// The environment map and textures on the device, for the next jobs.
    shared: buffers::Shared,
    /// What the device can hold (from its info; lower it to test).
    pub memory_limits: MemoryLimits,
    /// How adaptive work reaches the kernel.
    pub tile_dispatch: TileDispatch,
    /// Most pixels one launch covers ([`TILE`] on CPUs, [`GPU_TILE`] on
    /// GPUs; `PATHSTREAM_OPENCL_LAUNCH_PIXELS` sets it, to measure).
    pub launch_pixels: usize,
    /// Work-items per work-group ([`LOCAL_SIZE`];
    /// `PATHSTREAM_OPENCL_LOCAL_SIZE` sets it, to measure).
    pub local_size: usize,
    /// The film's floats as read back, kept between reads: a 1080p film is
    /// 100 MB, and allocating (zeroing) it anew cost more than the copy.
    staging: Staging,
}

impl Drop for OpenClBackend {
    fn drop(&mut self) {
        self.staging.release(&self.queue);
    }
}

impl std::fmt::Debug for OpenClBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OpenClBackend")
            .field("device", &self.info.name)
            .finish()
    }
}

impl OpenClBackend {
    /// A backend on device `index` (as `pathstream devices` numbers them), or
    /// when `index` is None on the device `auto` picks (the GPU with the
    /// most compute units), else on device 0.
    pub fn new(index: Option<usize>) -> Result<Self, OpenClError> {
        let devices = list_devices().map_err(OpenClError::Unavailable)?;
        let info = match index {
            Some(i) => devices.get(i).cloned().ok_or_else(|| {
                OpenClError::Unavailable(format!(
                    "--device {i}: there are {} OpenCL devices (0..{})",
                    devices.len(),
                    devices.len()
                ))
            })?,
            // A GPU box may list a CPU platform (PoCL) first.
            None => auto_pick(&devices)
                .or(devices.first())
                .cloned()
                .ok_or_else(|| OpenClError::Unavailable("no device".into()))?,
        };
        Self::on(info)
    }

    /// A backend on the GPU `auto` picks; Err says why there is none.
    pub fn auto() -> Result<Self, OpenClError> {
        let devices = list_devices().map_err(OpenClError::Unavailable)?;
        let gpu = auto_pick(&devices)
            .cloned()
            .ok_or_else(|| OpenClError::Unavailable("no OpenCL GPU (only CPU devices)".into()))?;
        Self::on(gpu)
    }

    fn on(info: DeviceInfo) -> Result<Self, OpenClError> {
        let context = Context::from_device(&info.device).map_err(call("context creation"))?;
        #[allow(deprecated)] // clCreateCommandQueue: OpenCL 1.2 devices have only this one
        let queue =
            CommandQueue::create_default(&context, 0).map_err(call("command queue creation"))?;
        let known = |b: u64| if b > 0 { b } else { u64::MAX };
        let info_is_gpu = info.kind == "gpu";
        let memory_limits = MemoryLimits {
            max_alloc_bytes: known(info.max_alloc_bytes),
            total_bytes: known(info.global_mem_bytes),
        };
        Ok(Self {
            info,
            context,
            queue,
            programs: HashMap::new(),
            states: Vec::new(),
            generic: false,
            inject_nan_every: None,
            fail_launches: false,
            fail_after_launches: None,
            launch_target: if info_is_gpu {
                GPU_LAUNCH_TARGET
            } else {
                LAUNCH_TARGET
            },
            last_upload: None,
            scene_bytes_uploaded: 0,
            shared: buffers::Shared::default(),
            memory_limits,
            tile_dispatch: TileDispatch::default(),
            launch_pixels: env_usize("PATHSTREAM_OPENCL_LAUNCH_PIXELS").unwrap_or(if info_is_gpu {
                GPU_TILE
            } else {
                TILE
            }),
            local_size: env_usize("PATHSTREAM_OPENCL_LOCAL_SIZE").unwrap_or(LOCAL_SIZE),
            staging: Staging::new(),
        })
    }

    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    pub fn device(&self) -> String {
        self.info.describe()
    }

    fn key_for(&self, job: &RenderJob) -> ProgramKey {
        if self.generic {
            ProgramKey::Generic {
                inject_nan_every: self.inject_nan_every,
                features: job.settings.features,
            }
        } else {
            let mut f = Features::of(job);
            f.inject_nan_every = self.inject_nan_every;
            ProgramKey::Specialised(f)
        }
    }

    /// Builds (or finds in the cache) the program for `key`.
    pub fn program(&mut self, key: &ProgramKey) -> Result<&Kernel, OpenClError> {
        if !self.programs.contains_key(key) {
            let start = Instant::now();
            let options = format!("{}{}", key.build_options(), self.device_options());
            let program = program::build(&self.context, &SOURCES, &options).map_err(|log| {
                OpenClError::Build {
                    device: self.info.name.trim().to_owned(),
                    log,
                }
            })?;
            let kernel = Kernel::create(&program, "render").map_err(call("kernel creation"))?;
            if let Ok(log) = program.get_build_log(self.info.device.id()) {
                if !log.trim().is_empty() {
                    tracing::info!(log = %log.trim(), "OpenCL build log");
                }
            }
            tracing::info!(options = %options, ms = start.elapsed().as_millis() as u64, "built OpenCL program");
            self.programs.insert(key.clone(), (program, kernel));
        }
        self.programs
            .get(key)
            .map(|(_, k)| k)
            .ok_or_else(|| OpenClError::Unavailable("program cache".into()))
    }

    /// Options this device's programs are built with on top of the
    /// program's own: division and sqrt correctly rounded where the device
    /// can, as on the CPU, a Sobol path's first points made ahead on CPU
    /// devices (`SAMPLER_AHEAD`), and `PATHSTREAM_OPENCL_OPTIONS` (to measure
    /// a compiler option; docs/OPENCL.md has what each costs).
    pub fn device_options(&self) -> String {
        let mut o = String::new();
        if self.info.correctly_rounded_divide_sqrt {
            o.push_str(" -cl-fp32-correctly-rounded-divide-sqrt");
        }
        let extra = std::env::var("PATHSTREAM_OPENCL_OPTIONS").unwrap_or_default();
        // A CPU device makes a Sobol path's first points ahead, side by side
        // (kernels/rng.h); GPUs keep them lazy unless the options say.
        if self.info.kind == "cpu" && !extra.contains("SAMPLER_AHEAD") {
            o.push_str(" -D SAMPLER_AHEAD=1");
        }
        if !extra.is_empty() {
            o.push(' ');
            o.push_str(&extra);
        }
        o
    }

    /// Builds arbitrary sources (tests: a broken kernel must fail with its
    /// log); the shared constants are always defined.
    pub fn build_sources(&self, sources: &[&str], options: &str) -> Result<Program, OpenClError> {
        let options = if options.contains(&shared_defines()) {
            options.to_owned()
        } else {
            format!("{options} {}", shared_defines())
        };
        program::build(&self.context, sources, &options).map_err(|log| OpenClError::Build {
            device: self.info.name.trim().to_owned(),
            log,
        })
    }

    /// `sizeof` of each shared struct as the device compiler sees it:
    /// (Object, Material, Params, BvhNode, Light, Instance, TriVerts).
    pub fn device_layout_sizes(&self) -> Result<[u32; 7], OpenClError> {
        let out: Vec<u32> = self.checks("")?.run("check_layout_sizes", 1, 7, &[])?;
        Ok(std::array::from_fn(|i| out[i]))
    }

    /// The device's compensated sum of `count` copies of `value` (hi + lo),
    /// computed with the film's own addition.
    pub fn accumulate_constant(&self, value: f32, count: u32) -> Result<f64, OpenClError> {
        let out: Vec<f32> = self.checks("")?.run(
            "check_accumulate",
            1,
            2,
            &[CheckArg::F32(value), CheckArg::U32(count)],
        )?;
        Ok(f64::from(out[0]) + f64::from(out[1]))
    }

    /// A device buffer of `count` elements (at least 1: OpenCL refuses empty
    /// buffers), uninitialised.
    fn buffer<T: Pod>(&self, access: Access, count: usize) -> Result<Buffer<T>, OpenClError> {
        #[allow(unsafe_code)]
        // SAFETY: the host pointer is null and `access` never asks OpenCL to
        // read it; the size is computed by opencl3 from `count.max(1)` and T.
        let buf = unsafe {
            Buffer::<T>::create(&self.context, access.flags(), count.max(1), ptr::null_mut())
        };
        buf.map_err(call("buffer allocation"))
    }

    /// A device buffer holding a copy of `data`.
    fn upload<T: Pod>(&self, access: Access, data: &[T]) -> Result<Buffer<T>, OpenClError> {
        let mut buf = self.buffer::<T>(access, data.len())?;
        if !data.is_empty() {
            #[allow(unsafe_code)]
            // SAFETY: a blocking write: OpenCL is done with `data` when the
            // call returns; the buffer holds `data.len()` elements; T: Pod has
            // no padding or pointers, only the plain values the kernel reads.
            unsafe {
                self.queue
                    .enqueue_write_buffer(&mut buf, CL_BLOCKING, 0, data, &[])
            }
            .map_err(call("write"))?;
        }
        Ok(buf)
    }

    /// Makes the device hold `job` and a film equal to the host's, as the
    /// most recently used state (uploading only when it does not already).
    fn prepare(
        &mut self,
        job: &RenderJob,
        film: &Film,
        key: &ProgramKey,
    ) -> Result<(), OpenClError> {
        let matches = |s: &JobState| {
            s.job_id == job.id
                && &s.key == key
                && s.first == film.first_sample()
                && s.spp == film.spp()
                && s.next == film.slice_start()
                && s.samples == film.total_samples()
                && s.pixels == film.pixels().len()
        };
        if let Some(i) = self.states.iter().position(matches) {
            let s = self.states.remove(i);
            self.states.push(s);
            return Ok(());
        }
        // A new, empty block of the same job (a render split across
        // devices takes one per pass): zero the device film in place and
        // keep the scene.
        let empty = film.total_samples() == 0 && film.slice_start() == 0;
        let same_job =
            |s: &JobState| s.job_id == job.id && &s.key == key && s.pixels == film.pixels().len();
        if let Some(i) = self.states.iter().position(same_job).filter(|_| empty) {
            let mut s = self.states.remove(i);
            #[allow(unsafe_code)]
            // SAFETY: fills the film buffer's `pixels` x FILM_FLOATS floats
            // (its whole size) with zeros; the in-order queue runs it before
            // any later launch or read.
            unsafe {
                self.queue.enqueue_fill_buffer(
                    &mut s.film,
                    &[0f32],
                    0,
                    s.pixels * FILM_FLOATS * std::mem::size_of::<f32>(),
                    &[],
                )
            }
            .map_err(call("film clear"))?;
            self.clear_guides(&mut s)?;
            (s.first, s.spp, s.next, s.samples) = (film.first_sample(), 0, 0, 0);
            self.states.push(s);
            return Ok(());
        }
        let per_sample = self
            .states
            .iter()
            .rev()
            .find(|s| s.job_id == job.id)
            .and_then(|s| s.per_sample);
        self.states.retain(|s| s.job_id != job.id);
        let upload_start = Instant::now();
        let packed = layout::pack(job);
        // Fits the device? (Other jobs' states make room if they must.)
        let guided = job.settings.features;
        let per_pixel = FILM_FLOATS + if guided { guides::GUIDE_FLOATS } else { 0 };
        let needed = buffers::job_bytes(&packed, film.pixels().len() * per_pixel * 4);
        buffers::check_fits(&needed, self.memory_limits).map_err(OpenClError::Unsupported)?;
        let bytes: usize = needed.iter().map(|(_, b)| b).sum();
        while !self.states.is_empty()
            && (self.states.iter().map(|s| s.bytes).sum::<usize>() + bytes) as u64
                > self.memory_limits.total_bytes
        {
            self.states.remove(0);
        }
        let film_floats = film.pixels().len() * FILM_FLOATS;
        let device_film = if film.total_samples() == 0 && film.slice_start() == 0 {
            // A fresh film (every change of view starts one) is zeroed on
            // the device, not uploaded (100 MB at 1080p).
            let mut b = self.buffer::<f32>(Access::ReadWrite, film_floats)?;
            #[allow(unsafe_code)]
            // SAFETY: fills the whole new buffer (film_floats floats) with
            // zeros; the in-order queue runs it before any launch or read.
            unsafe {
                self.queue
                    .enqueue_fill_buffer(&mut b, &[0f32], 0, film_floats * 4, &[])
            }
            .map_err(call("film clear"))?;
            b
        } else {
            self.upload(Access::ReadWrite, &host_film(film))?
        };
        let mut shared = std::mem::take(&mut self.shared);
        let (scene, uploaded) = buffers::SceneBuffers::upload(self, &packed, &mut shared)?;
        self.shared = shared;
        self.scene_bytes_uploaded += uploaded as u64;
        let state = JobState {
            job_id: job.id,
            key: key.clone(),
            scene,
            film: device_film,
            guides: self.guide_buffer(film, guided)?,
            guided,
            rejected: self.upload(Access::ReadWrite, &[0u32])?,
            pixels: film.pixels().len(),
            first: film.first_sample(),
            spp: film.spp(),
            next: film.slice_start(),
            samples: film.total_samples(),
            work: self.buffer(Access::ReadOnly, 1)?,
            work_capacity: 1,
            per_sample,
            rejected_reported: 0,
            bytes,
        };
        self.states.push(state);
        self.last_upload = Some((upload_start.elapsed(), bytes));
        // Keep at most RESIDENT_JOBS states and RESIDENT_FILM_BYTES of films.
        let film_bytes = |s: &JobState| s.pixels * FILM_FLOATS * 4;
        while self.states.len() > 1
            && (self.states.len() > RESIDENT_JOBS
                || self.states.iter().map(film_bytes).sum::<usize>() > RESIDENT_FILM_BYTES)
        {
            self.states.remove(0);
        }
        Ok(())
    }

    /// Builds (or finds) the program `job` needs.
    pub fn prepare_program(&mut self, job: &RenderJob) -> Result<(), OpenClError> {
        if let Some(why) = unsupported(job, &self.info) {
            return Err(OpenClError::Unsupported(why));
        }
        let key = self.key_for(job);
        self.program(&key).map(|_| ())
    }

    /// Makes the device ready to add to `film` for `job`: the program built
    /// (or found) and the job's state on the device; the program's key.
    fn ready(&mut self, job: &RenderJob, film: &Film) -> Result<ProgramKey, OpenClError> {
        if let Some(why) = unsupported(job, &self.info) {
            return Err(OpenClError::Unsupported(why));
        }
        let key = self.key_for(job);
        self.program(&key)?;
        self.prepare(job, film, &key)?;
        Ok(key)
    }
}

/// The device film's floats holding `film` (each half's f64 sums as a pair
/// of f32s, hi and lo).
fn host_film(film: &Film) -> Vec<f32> {
    let mut device_film = vec![0f32; film.pixels().len() * FILM_FLOATS];
    for (px, out) in film
        .pixels()
        .iter()
        .zip(device_film.chunks_exact_mut(FILM_FLOATS))
    {
        for c in 0..3 {
            for (half, base) in [(px.even[c], 0), (px.odd[c], FILM_FLOATS / 2)] {
                let hi = half as f32;
                out[base + c] = hi;
                out[base + 3 + c] = (half - f64::from(hi)) as f32;
            }
        }
    }
    device_film
}
