//! Routine checks: single kernel routines (`kernels/checks.cl`) run on the
//! device on inputs the host chooses, so that each can be compared with its
//! Rust twin on the same inputs (`tests/opencl_parity.rs`): the random
//! numbers bit for bit, the arithmetic within a few ulps.

use super::program::{check_sources, common_options};
use super::{call, Access, OpenClBackend, OpenClError};
use bytemuck::Pod;
use opencl3::kernel::Kernel;
use opencl3::memory::{Buffer, ClMem};
use opencl3::program::Program;
use opencl3::types::CL_BLOCKING;
use std::ptr;

/// An argument of a check kernel after its output buffer and item count.
pub enum CheckArg<'a> {
    /// A `__global const` buffer holding these bytes (any element type).
    Buffer(&'a [u8]),
    U32(u32),
    F32(f32),
}

/// The check program, built once for several checks.
pub struct Checks<'a> {
    backend: &'a OpenClBackend,
    program: Program,
    options: String,
}

impl OpenClBackend {
    /// Builds the kernel sources and the routine checks with the program's
    /// usual options and `extra` (to measure a compiler option's effect).
    pub fn checks(&self, extra: &str) -> Result<Checks<'_>, OpenClError> {
        let options = format!("{}{} {extra}", common_options(), self.device_options());
        let program = self.build_sources(&check_sources(), &options)?;
        Ok(Checks {
            backend: self,
            program,
            options,
        })
    }
}

impl Checks<'_> {
    /// The options the checks were built with.
    pub fn options(&self) -> &str {
        &self.options
    }

    /// Runs check kernel `name` over `items` work-items. Its arguments are
    /// `(__global O *out, uint n, args...)`, and item `i < n` writes
    /// `out[i * per_item ..][.. per_item]` only. Returns all outputs.
    pub fn run<O: Pod>(
        &self,
        name: &str,
        items: usize,
        per_item: usize,
        args: &[CheckArg],
    ) -> Result<Vec<O>, OpenClError> {
        let d = self.backend;
        let kernel = Kernel::create(&self.program, name).map_err(call("kernel creation"))?;
        let len = items * per_item;
        let out = d.buffer::<O>(Access::ReadWrite, len)?;
        let n = u32::try_from(items)
            .map_err(|_| OpenClError::Unavailable(format!("{items} check items")))?;
        // Kept alive until the blocking read below.
        let mut inputs: Vec<Buffer<u8>> = Vec::new();
        for a in args {
            if let CheckArg::Buffer(bytes) = a {
                inputs.push(d.upload::<u8>(Access::ReadOnly, bytes)?);
            }
        }
        #[allow(unsafe_code)]
        // SAFETY: argument 0 is `__global O *out`, a cl_mem of `len`
        // elements, as many as the kernel writes (`per_item` per item below
        // n); argument 1 is `uint n`; each further argument is a `__global`
        // pointer (a cl_mem), a `uint` or a `float`, in the order of `args`, which is
        // the kernel's signature by this function's contract.
        unsafe {
            kernel.set_arg(0, &out.get()).map_err(call("set_arg"))?;
            kernel.set_arg(1, &n).map_err(call("set_arg"))?;
            let mut buffers = inputs.iter();
            for (i, a) in args.iter().enumerate() {
                let index = (i + 2) as u32;
                match a {
                    CheckArg::Buffer(_) => {
                        let b = buffers.next().expect("one buffer per buffer argument");
                        kernel.set_arg(index, &b.get()).map_err(call("set_arg"))?;
                    }
                    CheckArg::U32(v) => kernel.set_arg(index, v).map_err(call("set_arg"))?,
                    CheckArg::F32(v) => kernel.set_arg(index, v).map_err(call("set_arg"))?,
                }
            }
        }
        let global = [items.max(1)];
        #[allow(unsafe_code)]
        // SAFETY: every argument is set; the buffers live until the blocking
        // read below has returned; `global` has `work_dim` (1) entries.
        unsafe {
            d.queue.enqueue_nd_range_kernel(
                kernel.get(),
                1,
                ptr::null(),
                global.as_ptr(),
                ptr::null(),
                &[],
            )
        }
        .map_err(call("launch"))?;
        let mut result = vec![O::zeroed(); len];
        if len > 0 {
            #[allow(unsafe_code)]
            // SAFETY: a blocking read of `len` elements, the buffer's size,
            // into `result`, which lives past the call; O: Pod takes any bytes.
            unsafe {
                d.queue
                    .enqueue_read_buffer(&out, CL_BLOCKING, 0, &mut result, &[])
            }
            .map_err(call("read"))?;
        }
        Ok(result)
    }
}
