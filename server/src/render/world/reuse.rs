//! What worlds build from their placed meshes alone (not from the camera),
//! kept for the next world: a camera move builds a new world, and should
//! not build these again. Each is keyed by the meshes it was built from
//! (weak references, so that a key's addresses cannot be reused while it
//! lives) and the exact bits of their placements. When full, the oldest
//! value that no world holds any more makes room first.

use crate::render::math::DAffine3;
use crate::render::shape::Mesh;
use std::sync::{Arc, Mutex, Weak};

/// A placed mesh as a key holds it: a tag (what the builder names it by),
/// the mesh, and its placement's bits.
type Key = Vec<(u32, Weak<Mesh>, [u64; 12])>;

/// A value the cache keeps, which may be held elsewhere too (by a world
/// still rendering).
pub(super) trait Held {
    /// Whether something besides the cache holds it.
    fn held_elsewhere(&self) -> bool;
}

impl<T> Held for Arc<T> {
    fn held_elsewhere(&self) -> bool {
        Arc::strong_count(self) > 1
    }
}

impl<T, U> Held for (Arc<T>, U) {
    fn held_elsewhere(&self) -> bool {
        self.0.held_elsewhere()
    }
}

/// The last few values built, the most recently used last.
pub(super) struct Reuse<V> {
    entries: Mutex<Vec<(Key, V)>>,
    capacity: usize,
}

impl<V: Clone + Held> Reuse<V> {
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
            // The oldest that no world holds goes first: a world still
            // rendering keeps its value for the next camera move (and
            // tests running side by side do not evict each other's).
            let unheld = entries.iter().position(|(_, v)| !v.held_elsewhere());
            entries.remove(unheld.unwrap_or(0));
        }
        entries.push((key, value.clone()));
        Ok(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::MeshData;

    fn mesh() -> Arc<Mesh> {
        let data = MeshData {
            name: "t".into(),
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            ..Default::default()
        };
        Arc::new(Mesh::new(data).expect("mesh"))
    }

    #[test]
    fn a_full_cache_keeps_what_a_world_still_holds() {
        let cache: Reuse<Arc<u32>> = Reuse::new(2);
        let meshes: Vec<Arc<Mesh>> = (0..4).map(|_| mesh()).collect();
        let at = DAffine3::IDENTITY;
        let builds = std::sync::atomic::AtomicU32::new(0);
        let get = |k: usize| {
            let placed = [(0, &meshes[k], &at)];
            let built = cache.get_or_build(&placed, || {
                Ok::<_, ()>(Arc::new(
                    builds.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
                ))
            });
            built.expect("built")
        };
        // The first value stays held (a world rendering); two more built
        // after it fill the cache past its size.
        let held = get(0);
        drop(get(1));
        drop(get(2));
        assert_eq!(get(0), held, "the held value was evicted");
        // Values nobody holds go oldest first: 1 went for 2.
        assert_eq!(*get(1), 3, "an unheld value was kept over a held one");
    }
}
