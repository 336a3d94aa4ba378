//! The scene as the hot path sees it: f32, relative to a render origin (the
//! camera position), with materials flattened and emitters listed.
//!
//! Working camera-relative is what makes the image independent of where the
//! scene sits in the world: a scene moved 1e6 units from the origin has the
//! same f32 coordinates here as one at the origin (the subtraction is done in
//! f64), so f32 only ever holds numbers of the scene's own size. Meshes stay
//! in their own object space (their BVHs are built once, whatever the
//! camera does); an instance maps rays into it. Small meshes are first
//! merged into one, placed in a scene frame by a translation (`merge`,
//! cached across camera moves): one traversal instead of one per mesh.
//!
//! Nearest hits are found by one of two accelerators, chosen per scene:
//! a scan of every object (spheres eight at a time, then quads), fastest
//! for the few objects of the thesis's scenes, or a BVH over all objects
//! whose mesh instances hold BVHs of their own (`bvh`). Both find the
//! same hit: among equal distances, the lowest (object, triangle).

mod build;
pub mod cutout;
mod embree_rays;
mod embree_scene;
mod emitters;
pub mod flat;
mod instance;
mod merge;
mod packet;
mod reuse;
mod scan;
mod textures;

pub use build::{scan_cost, AccelChoice, SCAN_MAX_COST};
pub use embree_rays::EMBREE_MIN_TRIANGLES;
pub use embree_scene::{EmbreeLayout, FLAT_MAX_TRIANGLES};
pub use instance::Instance;
pub use packet::PACKET_MAX_TRIANGLES;

use crate::render::bvh::{Aabb, BoxRay, Bvh};
#[cfg(target_arch = "x86_64")]
use crate::render::isa::{Avx2, Avx512};
use crate::render::isa::{Isa, Portable};
use crate::render::light::{EnvLight, Lights, Receiver};
use crate::render::material::{SurfaceMaterial, NO_MAPS};
use crate::render::math::{DVec3, Vec3A};
use crate::render::ray::Ray;
use crate::render::shape::{Quad, Roots, Sphere, SphereBatch};
use instance::Prepared;

/// `prim` of a hit or origin on an object that is not a mesh.
pub const NO_PRIM: u32 = u32::MAX;
/// `object` of no object.
pub const NO_OBJECT: u32 = u32::MAX;

/// An object's geometry; a closed set matched in one place (here).
#[derive(Clone, Copy, Debug)]
pub enum Geometry {
    Sphere(Sphere),
    Quad(Quad),
    /// A placed mesh: `World::instances[i]`.
    Instance(u32),
}

#[derive(Clone, Copy, Debug)]
pub struct WorldObject {
    pub geometry: Geometry,
    /// Spheres and quads; an instance's triangles map their own.
    pub material: u32,
}

/// The surface a ray starts on, so that it cannot hit it again: a ray
/// leaving a quad or a triangle never meets that (flat) primitive again; a
/// ray leaving a sphere outwards never meets it, one going into it meets
/// only its far side. Triangles also move the ray's origin off the surface
/// by the bound of its rounding error (`Surface::spawn`), for their
/// neighbours' sake.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Origin {
    pub object: u32,
    /// The triangle, for a mesh instance; else [`NO_PRIM`].
    pub prim: u32,
    pub entering: bool,
}

impl Origin {
    /// A ray that starts on no surface (camera rays).
    pub const NONE: Origin = Origin {
        object: NO_OBJECT,
        prim: NO_PRIM,
        entering: false,
    };
}

/// The nearest intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub object: u32,
    /// The triangle of a mesh instance, else [`NO_PRIM`].
    pub prim: u32,
    /// Barycentric weights of the triangle's vertices.
    pub bary: [f32; 3],
}

impl Hit {
    /// `a` where `take`, else `b`, field by field: conditional moves, not
    /// a branch (whether a path's ray hit is as good as random).
    #[inline(always)]
    pub fn select(take: bool, a: Hit, b: Hit) -> Hit {
        let mask = u32::from(take).wrapping_neg();
        let pick = |x: u32, y: u32| (x & mask) | (y & !mask);
        let pick_f = |x: f32, y: f32| f32::from_bits(pick(x.to_bits(), y.to_bits()));
        Hit {
            t: pick_f(a.t, b.t),
            object: pick(a.object, b.object),
            prim: pick(a.prim, b.prim),
            bary: std::array::from_fn(|i| pick_f(a.bary[i], b.bary[i])),
        }
    }

    /// Whether this is a hit ([`Hit::NONE`]'s infinite distance is none).
    #[inline(always)]
    pub fn found(&self) -> bool {
        self.t < f32::INFINITY
    }

    /// This hit, if it is one.
    #[inline(always)]
    pub fn some(self) -> Option<Hit> {
        self.found().then_some(self)
    }

    const NONE: Hit = Hit {
        t: f32::INFINITY,
        object: NO_OBJECT,
        prim: NO_PRIM,
        bary: [0.0; 3],
    };

    /// Takes (t, object, prim) if it comes before this hit: nearer, or as
    /// near with a lower (object, prim). So the nearest hit does not depend
    /// on the order in which a traversal offers candidates (a single ray's
    /// nearest-first walk, a packet's walk, the kernel's four-wide one):
    /// the triangle tests accept a hit at exactly the best distance so far
    /// for this rule to decide.
    #[inline(always)]
    fn offer(&mut self, t: f32, object: u32, prim: u32, bary: [f32; 3]) {
        if t < self.t || (t == self.t && (object, prim) < (self.object, self.prim)) {
            *self = Hit {
                t,
                object,
                prim,
                bary,
            };
        }
    }
}

/// Where a path met a surface, as shading needs it.
#[derive(Clone, Copy, Debug)]
pub struct Surface {
    pub p: Vec3A,
    /// Unit geometric normal (outward for spheres).
    pub ng: Vec3A,
    /// Unit shading normal: `ng`, or the mesh's interpolated normal.
    pub ns: Vec3A,
    /// A clear coat's own unit normal where its maps make it differ from
    /// `ns` ([`World::shade`]); zero: the coat lies on `ns`.
    pub nc: Vec3A,
    /// Whether `ns` differs from `ng` (a mesh with vertex normals): then a
    /// scattered direction must also be on the right side of `ng`.
    pub smooth: bool,
    pub material: u32,
    pub object: u32,
    pub prim: u32,
    /// For triangles: where to start rays that leave the surface.
    pub offset: Option<instance::Offset>,
}

impl Surface {
    /// The surface as light sampling sees it, with its geometric and
    /// shading normals `nl` and `ns` on the side the path arrived from.
    #[inline(always)]
    pub fn receiver(&self, nl: Vec3A, ns: Vec3A) -> Receiver {
        Receiver {
            p: self.p,
            object: self.object,
            prim: self.prim,
            nl,
            ns,
        }
    }
}

#[derive(Clone, Debug)]
enum Accel {
    Scan {
        /// The spheres again, several to a batch with their object
        /// indices, so that the nearest hit is found with lane-wise selects.
        sphere_batches: Vec<SphereBatch>,
        /// The quads again with their object indices.
        quads: Vec<(u32, Quad)>,
        /// Each object's box, for a device that searches by BVH what the
        /// CPU scans ([`World::device_bvh`]).
        boxes: Vec<Aabb>,
        /// That BVH and the objects tested before it, built on first use.
        bvh: std::sync::OnceLock<(Bvh, Vec<u32>)>,
    },
    /// A BVH over most objects; spheres that enclose the scene (smallpt's
    /// walls, a furnace shell) are scanned first instead, in batches:
    /// nearly every ray enters their boxes anyway, and their hit bounds the
    /// BVH search from the start.
    Bvh { bvh: Bvh, big: Vec<SphereBatch> },
}

#[derive(Clone, Debug)]
pub struct World {
    /// World-space position that is (0, 0, 0) here.
    pub origin: DVec3,
    pub objects: Vec<WorldObject>,
    pub instances: Vec<Instance>,
    pub materials: Vec<SurfaceMaterial>,
    /// The textures the materials' maps read (each once).
    pub textures: Vec<std::sync::Arc<crate::render::texture::Texture>>,
    /// Texture maps, by `SurfaceMaterial::maps`.
    pub maps: Vec<crate::render::maps::WorldMaps>,
    /// Some placed mesh has vertex colours (every hit is then shaded by
    /// [`World::shade`]).
    pub vertex_colors: bool,
    /// Some placed mesh is only translated (`Instance::translation_only`):
    /// rays are then prepared for the triangle test once, in camera space.
    pub translated_meshes: bool,
    /// Triangles of every placed mesh together (a mesh placed twice
    /// counted twice): what the choices of tracer go by.
    pub placed_triangles: usize,
    pub lights: Lights,
    /// Radiance of rays that leave the scene, where there is no map.
    pub environment: Vec3A,
    /// The environment map: radiance of rays that leave the scene (and its
    /// emitter is the last of `lights`). Diffuse surfaces then weigh their
    /// light and BSDF samples by multiple importance sampling, as `pbr`
    /// ones always do.
    pub env_map: Option<std::sync::Arc<EnvLight>>,
    /// A computed sky's sun and its radiance (its emitter is `lights.sun()`).
    pub sun: Option<(crate::render::light::SunLight, Vec3A)>,
    accel: Accel,
    /// What the world was asked for: `Auto` lets each backend choose by
    /// its own measurement; `Bvh` and `Scan` hold for every backend.
    pub accel_choice: AccelChoice,
    /// The meshes in Embree, once a CPU backend has asked for them
    /// ([`World::use_embree`]); None inside: Embree does not serve.
    embree: std::sync::OnceLock<Option<std::sync::Arc<embree_rays::EmbreeRays>>>,
}

impl World {
    /// The radiance that a ray leaving the scene along unit `dir` finds
    /// (a hidden map's background, which camera rays see, is no light).
    #[inline(always)]
    pub fn sky(&self, dir: Vec3A) -> Vec3A {
        match &self.env_map {
            None => self.environment,
            Some(m) => m.radiance(dir),
        }
    }

    /// Whether diffuse surfaces weigh light and BSDF samples by MIS (a
    /// scene with an environment map): else NEE alone lights them.
    #[inline(always)]
    pub fn diffuse_mis(&self) -> bool {
        self.env_map.is_some()
    }

    /// Whether nearest hits are found through a BVH (else by a scan).
    pub fn uses_bvh(&self) -> bool {
        matches!(self.accel, Accel::Bvh { .. })
    }

    /// The BVH over the objects, if the world uses one.
    pub fn object_bvh(&self) -> Option<&Bvh> {
        match &self.accel {
            Accel::Bvh { bvh, .. } => Some(bvh),
            Accel::Scan { .. } => None,
        }
    }

    /// The objects' BVH and the objects to test one by one before it
    /// (ascending), for a backend whose own measurement prefers the BVH:
    /// the world's own, or for a scanned world one built on first use.
    pub fn device_bvh(&self) -> (&Bvh, Vec<u32>) {
        match &self.accel {
            Accel::Bvh { bvh, .. } => (bvh, self.scanned_first()),
            Accel::Scan { boxes, bvh, .. } => {
                let (b, big) = bvh.get_or_init(|| build::object_bvh(&self.objects, boxes));
                (b, big.clone())
            }
        }
    }

    /// The objects a BVH world tests one by one before its BVH (spheres so
    /// large that they would fill every node's box), in ascending order;
    /// none for a scanned world.
    pub fn scanned_first(&self) -> Vec<u32> {
        match &self.accel {
            Accel::Bvh { big, .. } => big
                .iter()
                .flat_map(|b| b.ids)
                .filter(|&id| id >= 0.0)
                .map(|id| id as u32)
                .collect(),
            Accel::Scan { .. } => Vec::new(),
        }
    }

    /// Nearest hit along `ray`, never the surface the ray starts on; the
    /// spheres of a scan are tested with `isa`'s kernel.
    ///
    /// One copy of the BVH's traversal per instruction set, out of line:
    /// the render loop traces rays at a dozen places (path and shadow rays,
    /// of two paths, for each kind of surface), and inlined at each the
    /// loop took 0.8 MB of machine code per copy and most of the crate's
    /// build. Out of line it renders as fast (docs/BENCHMARKS.md, "The
    /// traversal out of line").
    #[inline(always)]
    pub fn intersect<I: Isa>(&self, isa: I, ray: &Ray, from: Origin) -> Option<Hit> {
        // A scan of a few spheres and quads stays inline: it is small, and
        // a call costs the sphere scenes 4%. A scanned world has no meshes,
        // so Embree (which serves only meshes) never traces it.
        if let Accel::Scan {
            sphere_batches,
            quads,
            ..
        } = &self.accel
        {
            debug_assert!(!matches!(self.embree.get(), Some(Some(_))));
            let hit = scan::nearest(isa, sphere_batches, quads, ray, from);
            return (hit.t < f32::INFINITY).then_some(hit);
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(avx512) = isa.avx512() {
            // SAFETY: an `Avx512` exists only where the CPU has AVX-512 F,
            // VL, BW and DQ, AVX2 and FMA.
            #[allow(unsafe_code)]
            return unsafe { self.nearest_avx512(avx512, ray, from) };
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(avx2) = isa.avx2() {
            // SAFETY: an `Avx2` exists only where the CPU has AVX2 and FMA.
            #[allow(unsafe_code)]
            return unsafe { self.nearest_avx2(avx2, ray, from) };
        }
        self.nearest_portable(ray, from)
    }

    /// [`World::nearest`] for every CPU.
    #[inline(never)]
    fn nearest_portable(&self, ray: &Ray, from: Origin) -> Option<Hit> {
        self.nearest(Portable, ray, from)
    }

    /// [`World::nearest`] compiled for AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[inline(never)]
    #[target_feature(enable = "avx2,fma")]
    fn nearest_avx2(&self, isa: Avx2, ray: &Ray, from: Origin) -> Option<Hit> {
        self.nearest(isa, ray, from)
    }

    /// [`World::nearest`] compiled for AVX-512, called from the render
    /// loop's AVX-512 copy.
    #[cfg(target_arch = "x86_64")]
    #[inline(never)]
    #[target_feature(enable = "avx2,fma,avx512f,avx512vl,avx512bw,avx512dq")]
    fn nearest_avx512(&self, isa: Avx512, ray: &Ray, from: Origin) -> Option<Hit> {
        self.nearest(isa, ray, from)
    }

    /// [`World::intersect`]'s traversal, inlined into each copy.
    #[inline(always)]
    fn nearest<I: Isa>(&self, isa: I, ray: &Ray, from: Origin) -> Option<Hit> {
        if let Some(Some(embree)) = self.embree.get() {
            let hit = embree.nearest(self, isa, ray, from);
            return (hit.t < f32::INFINITY).then_some(hit);
        }
        let hit = match &self.accel {
            Accel::Scan {
                sphere_batches,
                quads,
                ..
            } => scan::nearest(isa, sphere_batches, quads, ray, from),
            Accel::Bvh { bvh, big } => {
                let mut best = if big.is_empty() {
                    Hit::NONE
                } else {
                    scan::nearest(isa, big, &[], ray, from)
                };
                let boxes = BoxRay::new(ray.origin, ray.dir);
                // Only where some instance shares it: scenes of spheres and
                // quads alone skip the triangle set-up.
                let pre = self.translated_meshes.then(|| Prepared::new(ray, boxes));
                let mut walk = bvh.walk(boxes);
                while let Some((first, count)) = walk.next_leaf(best.t) {
                    for slot in first..first + count {
                        self.offer_object::<false, I>(
                            isa,
                            bvh.prims[slot as usize],
                            (ray, pre.as_ref()),
                            from,
                            &mut best,
                        );
                    }
                }
                best
            }
        };
        (hit.t < f32::INFINITY).then_some(hit)
    }

    /// The nearest hit found by testing every object and every triangle,
    /// without any acceleration: what `intersect` must agree with.
    pub fn intersect_brute(&self, ray: &Ray, from: Origin) -> Option<Hit> {
        let mut best = Hit::NONE;
        let pre = Prepared::new(ray, BoxRay::new(ray.origin, ray.dir));
        for id in 0..self.objects.len() as u32 {
            self.offer_object::<true, _>(Portable, id, (ray, Some(&pre)), from, &mut best);
        }
        (best.t < f32::INFINITY).then_some(best)
    }

    #[inline(always)]
    fn offer_object<const BRUTE: bool, I: Isa>(
        &self,
        isa: I,
        id: u32,
        (ray, pre): (&Ray, Option<&Prepared>),
        from: Origin,
        best: &mut Hit,
    ) {
        match &self.objects[id as usize].geometry {
            Geometry::Sphere(s) => {
                let roots = match (id == from.object, from.entering) {
                    (false, _) => Roots::Any,
                    (true, true) => Roots::FarOnly,
                    (true, false) => return,
                };
                best.offer(s.intersect(ray, roots), id, NO_PRIM, [0.0; 3]);
            }
            Geometry::Quad(q) => {
                if id != from.object {
                    best.offer(q.intersect(ray), id, NO_PRIM, [0.0; 3]);
                }
            }
            Geometry::Instance(i) => {
                let skip = if id == from.object {
                    from.prim
                } else {
                    NO_PRIM
                };
                self.instances[*i as usize].offer::<BRUTE, I>(isa, id, (ray, pre), skip, best);
            }
        }
    }

    /// The surface at `hit`, found along `ray`.
    #[inline(always)]
    pub fn surface(&self, hit: &Hit, ray: &Ray) -> Surface {
        let o = &self.objects[hit.object as usize];
        let flat = |p: Vec3A, n: Vec3A| Surface {
            p,
            ng: n,
            ns: n,
            nc: Vec3A::ZERO,
            smooth: false,
            material: o.material,
            object: hit.object,
            prim: NO_PRIM,
            offset: None,
        };
        match &o.geometry {
            Geometry::Sphere(s) => {
                let p = ray.at(hit.t);
                flat(p, s.normal(p))
            }
            Geometry::Quad(q) => flat(ray.at(hit.t), q.normal),
            Geometry::Instance(i) => self.instances[*i as usize].surface(hit, *i),
        }
    }

    /// Starts loading what [`World::surface`] will read for `hit` (a
    /// mesh's vertices and normals; nothing for spheres and quads, whose
    /// surfaces need no lookup).
    #[inline(always)]
    pub fn prefetch_surface(&self, hit: &Hit) {
        if let Some(o) = self.objects.get(hit.object as usize) {
            if let Geometry::Instance(i) = o.geometry {
                self.instances[i as usize].mesh.prefetch_surface(hit.prim);
            }
        }
    }

    /// A ray from surface `s` along `dir`, starting where it cannot meet
    /// `s` again by rounding.
    #[inline(always)]
    pub fn spawn(&self, s: &Surface, dir: Vec3A) -> Ray {
        match &s.offset {
            None => Ray::new(s.p, dir),
            Some(off) => Ray::new(
                self.instances[off.instance as usize].spawn_origin(off, s.ng, dir),
                dir,
            ),
        }
    }

    #[inline(always)]
    pub fn material(&self, index: u32) -> &SurfaceMaterial {
        &self.materials[index as usize]
    }

    /// Material `m` as it is at `hit` on surface `s`: its maps read (if it
    /// has any), `s`'s shading normal turned by its normal map (and its
    /// coat's normal set where that differs), the base
    /// colour times the mesh's vertex colour (if it has them). Not inlined:
    /// its lookups would crowd the path loop of every scene, textured or
    /// not (a call costs little next to four bilinear reads).
    #[inline(never)]
    pub fn shade(&self, m: &SurfaceMaterial, hit: &Hit, s: &mut Surface) -> SurfaceMaterial {
        let mut out = *m;
        if m.maps != NO_MAPS {
            let maps = &self.maps[m.maps as usize];
            let tc = self.texcoords(hit, s);
            let (mut ns, mut nc) = (s.ns, Vec3A::ZERO);
            out = crate::render::maps::shade(&self.textures, maps, m, &tc, (&mut ns, &mut nc));
            if nc != ns && nc != Vec3A::ZERO {
                s.nc = nc;
                s.smooth = true;
            }
            if ns != s.ns {
                s.ns = ns;
                s.smooth = true;
            }
        }
        if let Geometry::Instance(i) = self.objects[hit.object as usize].geometry {
            if let Some(c) = self.instances[i as usize].mesh.color(hit.prim, hit.bary) {
                out.albedo *= c;
            }
        }
        out
    }
}
