//! Host memory the film is read back into, kept between reads: page-locked
//! where the driver gives it (a buffer allocated with
//! `CL_MEM_ALLOC_HOST_PTR` and kept mapped, the way NVIDIA's OpenCL
//! reaches full transfer speed; a read into pageable memory goes through a
//! driver buffer in pieces), else an ordinary `Vec`.
//! `PATHSTREAM_OPENCL_PINNED=0` reads into the `Vec` (to measure).

use opencl3::command_queue::CommandQueue;
use opencl3::context::Context;
use opencl3::memory::{Buffer, ClMem, CL_MAP_READ, CL_MAP_WRITE, CL_MEM_ALLOC_HOST_PTR};
use opencl3::types::{cl_mem, CL_BLOCKING};
use std::ptr;

/// A host-accessible buffer and where it is mapped.
struct Mapped {
    buffer: Buffer<f32>,
    ptr: *mut f32,
    len: usize,
}

// SAFETY: the pointer is the mapping of `buffer`, which moves with it; only
// the owner of the `Mapped` reads or writes through it.
#[allow(unsafe_code)]
unsafe impl Send for Mapped {}

pub struct Staging {
    mapped: Option<Mapped>,
    plain: Vec<f32>,
    pinned: bool,
}

impl Staging {
    pub fn new() -> Self {
        Self {
            mapped: None,
            plain: Vec::new(),
            pinned: std::env::var("PATHSTREAM_OPENCL_PINNED").map_or(true, |v| v != "0"),
        }
    }

    /// `floats` floats of host memory (contents unspecified: a read fills
    /// them).
    pub fn get(&mut self, context: &Context, queue: &CommandQueue, floats: usize) -> &mut [f32] {
        if self.pinned && self.mapped.as_ref().is_none_or(|m| m.len < floats) {
            self.release(queue);
            match map(context, queue, floats) {
                Ok(m) => self.mapped = Some(m),
                Err(e) => {
                    tracing::warn!(error = %e, "no page-locked read-back memory: reading into pageable memory");
                    self.pinned = false;
                }
            }
        }
        match &mut self.mapped {
            #[allow(unsafe_code)]
            // SAFETY: the mapping covers m.len >= floats f32s (zeroed when it
            // was made), stays valid until `release`, and is borrowed through
            // &mut self only.
            Some(m) => unsafe { std::slice::from_raw_parts_mut(m.ptr, floats) },
            None => {
                if self.plain.len() < floats {
                    self.plain = vec![0f32; floats];
                }
                &mut self.plain[..floats]
            }
        }
    }

    /// Unmaps the page-locked buffer (before it, or the queue, goes).
    pub fn release(&mut self, queue: &CommandQueue) {
        if let Some(m) = self.mapped.take() {
            #[allow(unsafe_code)]
            // SAFETY: m.ptr is the pointer the map of m.buffer returned and
            // no slice of it outlives this call (`get` borrows self).
            let unmapped =
                unsafe { queue.enqueue_unmap_mem_object(m.buffer.get(), m.ptr.cast(), &[]) };
            if unmapped.is_ok() {
                let _ = queue.finish();
            }
        }
    }
}

/// A new page-locked buffer of `floats` floats, mapped and zeroed.
fn map(context: &Context, queue: &CommandQueue, floats: usize) -> Result<Mapped, String> {
    let bytes = floats * std::mem::size_of::<f32>();
    #[allow(unsafe_code)]
    // SAFETY: no host pointer is given (the driver allocates).
    let buffer = unsafe {
        Buffer::<f32>::create(
            context,
            opencl3::memory::CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR,
            floats.max(1),
            ptr::null_mut(),
        )
    }
    .map_err(|e| e.to_string())?;
    let mut mapped: cl_mem = ptr::null_mut();
    #[allow(unsafe_code)]
    // SAFETY: a blocking map of the whole buffer; the pointer is checked below.
    unsafe {
        queue.enqueue_map_buffer(
            &buffer,
            CL_BLOCKING,
            CL_MAP_READ | CL_MAP_WRITE,
            0,
            bytes,
            &mut mapped,
            &[],
        )
    }
    .map_err(|e| e.to_string())?;
    let ptr = mapped.cast::<f32>();
    if ptr.is_null() || !ptr.is_aligned() {
        return Err("the map returned no aligned pointer".into());
    }
    #[allow(unsafe_code)]
    // SAFETY: the mapping is `bytes` long and writable.
    unsafe {
        ptr.write_bytes(0, floats)
    };
    Ok(Mapped {
        buffer,
        ptr,
        len: floats,
    })
}
