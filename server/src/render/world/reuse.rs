//! What worlds build from their placed meshes alone (not from the camera),
//! kept for the next world: a camera move builds a new world, and should
//! not build these again. Each is keyed by the meshes it was built from
//! (weak references, so that a key's addresses cannot be reused while it
//! lives) and the exact bits of their placements.

use crate::render::math::DAffine3;
use crate::render::shape::Mesh;
use std::sync::{Arc, Mutex, Weak};

/// A placed mesh as a key holds it: a tag (what the builder names it by),
/// the mesh, and its placement's bits.
type Key = Vec<(u32, Weak<Mesh>, [u64; 12])>;

/// The last few values built, the most recently used last.
pub(super) struct Reuse<V> {
    entries: Mutex<Vec<(Key, V)>>,
    capacity: usize,
}

impl<V: Clone> Reuse<V> {
    /// A cache of at most `capacity` values.
    pub const fn new(capacity: usize) -> Self {
        Self {
            entries: Mutex::new(Vec::new()),
            capacity,
        }
    }

    /// The value built from `placed` (each `(tag, mesh, world_from_object)`),
    /// from the cache, or built by `build` and kept (an error is not).
    pub fn get_or_build<E>(
        &self,
        placed: &[(u32, &Arc<Mesh>, &DAffine3)],
        build: impl FnOnce() -> Result<V, E>,
    ) -> Result<V, E> {
        let bits = |a: &DAffine3| a.to_cols_array().map(f64::to_bits);
        let same = |key: &Key| {
            key.len() == placed.len()
                && key.iter().zip(placed).all(|((tag, mesh, at), (t, m, a))| {
                    tag == t && std::ptr::eq(mesh.as_ptr(), Arc::as_ptr(m)) && *at == bits(a)
                })
        };
        {
            let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
            // Values built from meshes no scene holds any more go at once.
            entries.retain(|(key, _)| key.iter().all(|(_, m, _)| m.strong_count() > 0));
            if let Some(i) = entries.iter().position(|(key, _)| same(key)) {
                let entry = entries.remove(i);
                let found = entry.1.clone();
                entries.push(entry);
                return Ok(found);
            }
        }
        let value = build()?;
        let key = (placed.iter())
            .map(|&(tag, m, a)| (tag, Arc::downgrade(m), bits(a)))
            .collect();
        let mut entries = self.entries.lock().unwrap_or_else(|e| e.into_inner());
        if entries.len() >= self.capacity {
            entries.remove(0);
        }
        entries.push((key, value.clone()));
        Ok(value)
    }
}
