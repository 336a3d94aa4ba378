//! `mesh` and `model` objects: their source resolved, their materials
//! added to the scene's, their placements composed with their transform.
//!
//! - A `mesh` places every mesh of its file (or its inline `data`) by its
//!   `transform`; `material` (required for inline data) replaces the
//!   file's materials on every triangle.
//! - A `model` places a whole file: meshes, node hierarchy, materials; its
//!   camera is the scene's when the scene gives none.
//!
//! A file's materials join the scene's as `file/name` (not written back to
//! JSON: the file brings them). The same file placed twice is loaded once,
//! its meshes stored once.

use super::json::{ImportJson, MeshDataJson};
use super::resolve::{LoadedModel, ModelSource, Resolver};
use super::{materials, placement, Material, SceneError};
use crate::render::math::DAffine3;
use crate::render::shape::{Mesh, MeshData};
use std::collections::{BTreeMap, HashMap};
use std::hash::{Hash, Hasher};
use std::sync::{Arc, Mutex, OnceLock, Weak};

type Result<T> = std::result::Result<T, SceneError>;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImportKind {
    Mesh,
    Model,
}

/// One `mesh` or `model` object, loaded and placed.
#[derive(Clone, Debug)]
pub struct Import {
    pub kind: ImportKind,
    /// The object as given (to write the scene back as JSON).
    pub json: ImportJson,
    pub model: Arc<LoadedModel>,
    /// The object's own `transform`.
    pub world_from_json: DAffine3,
    pub instances: Vec<MeshInstance>,
}

impl PartialEq for Import {
    fn eq(&self, o: &Self) -> bool {
        self.kind == o.kind
            && self.json == o.json
            && Arc::ptr_eq(&self.model, &o.model)
            && self.world_from_json == o.world_from_json
            && self.instances == o.instances
    }
}

/// A mesh placed in the world.
#[derive(Clone, Debug)]
pub struct MeshInstance {
    pub mesh: Arc<Mesh>,
    pub world_from_object: DAffine3,
    /// Scene material of each of the mesh's material slots.
    pub materials: Arc<[u32]>,
}

impl PartialEq for MeshInstance {
    fn eq(&self, o: &Self) -> bool {
        Arc::ptr_eq(&self.mesh, &o.mesh)
            && self.world_from_object == o.world_from_object
            && self.materials == o.materials
    }
}

/// Imports objects into a scene under validation.
pub(super) struct Importer<'a> {
    pub resolver: &'a dyn Resolver,
    pub materials: &'a mut Vec<Material>,
    pub index_of: &'a mut BTreeMap<String, usize>,
    /// Scene material of every material of a model already imported.
    pub added: HashMap<*const LoadedModel, Arc<[u32]>>,
}

impl Importer<'_> {
    /// The import for object `path`, and the material its object reports.
    pub fn import(
        &mut self,
        path: &str,
        kind: ImportKind,
        json: &ImportJson,
    ) -> Result<(Import, usize)> {
        let sources = [
            json.file.is_some(),
            json.asset.is_some(),
            json.data.is_some(),
        ];
        if sources.iter().filter(|&&s| s).count() != 1 {
            let what = match kind {
                ImportKind::Mesh => "give exactly one of file, asset or data",
                ImportKind::Model => "give exactly one of file or asset",
            };
            return Err(SceneError::new(path, what));
        }
        if kind == ImportKind::Model {
            if json.data.is_some() {
                return Err(SceneError::new(
                    format!("{path}.data"),
                    "inline data makes a mesh, not a model",
                ));
            }
            if json.material.is_some() {
                return Err(SceneError::new(
                    format!("{path}.material"),
                    "a model keeps its own materials; use a mesh to give one material to every triangle",
                ));
            }
        }
        let model = match (&json.data, ModelSource::of(json)) {
            (Some(data), _) => {
                inline(data).map_err(|e| SceneError::new(format!("{path}.data"), e))?
            }
            (None, Some(source)) => {
                let field = if json.file.is_some() { "file" } else { "asset" };
                self.resolver
                    .resolve(source)
                    .map_err(|e| SceneError::new(format!("{path}.{field}"), e))?
            }
            (None, None) => {
                return Err(SceneError::new(
                    path,
                    "give exactly one of file, asset or data",
                ))
            }
        };
        let world_from_json =
            placement::world_from_object(&format!("{path}.transform"), json.transform.as_ref())?;
        let map: Arc<[u32]> = match &json.material {
            Some(name) => {
                let Some(&m) = self.index_of.get(name) else {
                    return Err(materials::unknown_material(
                        &format!("{path}.material"),
                        name,
                        self.index_of,
                    ));
                };
                vec![m as u32; model.materials.len().max(1)].into()
            }
            None if model.materials.is_empty() => {
                return Err(SceneError::new(
                    format!("{path}.material"),
                    "this mesh has no materials of its own: name one of the scene's",
                ))
            }
            None => self.model_materials(path, &model)?,
        };
        let mut instances = Vec::with_capacity(model.instances.len());
        for &(mesh, world_from_object) in &model.instances {
            let mesh = model
                .meshes
                .get(mesh)
                .ok_or_else(|| SceneError::new(path, "the model places a mesh it does not have"))?;
            if mesh.material_slots as usize > map.len() {
                return Err(SceneError::new(
                    path,
                    format!(
                        "mesh '{}' uses more materials than the model has",
                        mesh.name
                    ),
                ));
            }
            instances.push(MeshInstance {
                mesh: mesh.clone(),
                world_from_object: world_from_json * world_from_object,
                materials: map.clone(),
            });
        }
        let material = instances
            .first()
            .map_or(map[0], |i| map[i.mesh.materials[0] as usize]) as usize;
        let import = Import {
            kind,
            json: json.clone(),
            model,
            world_from_json,
            instances,
        };
        Ok((import, material))
    }

    /// Adds `model`'s materials to the scene's (once per model).
    fn model_materials(&mut self, path: &str, model: &Arc<LoadedModel>) -> Result<Arc<[u32]>> {
        if let Some(map) = self.added.get(&Arc::as_ptr(model)) {
            return Ok(map.clone());
        }
        let mut map = Vec::with_capacity(model.materials.len());
        for (name, m, maps) in &model.materials {
            let mut full = format!("{}/{name}", model.name);
            let mut n = 2;
            while self.index_of.contains_key(&full) {
                full = format!("{}/{name} ({n})", model.name);
                n += 1;
            }
            let mut material = materials::material(&full, m, self.resolver)
                .map_err(|e| SceneError::new(path, format!("{}: {e}", model.name)))?;
            material.imported = true;
            material.maps = maps.clone();
            self.index_of.insert(full, self.materials.len());
            map.push(self.materials.len() as u32);
            self.materials.push(material);
        }
        let map: Arc<[u32]> = map.into();
        self.added.insert(Arc::as_ptr(model), map.clone());
        Ok(map)
    }
}

/// Inline meshes built, by a hash of their data, for as long as a scene holds them.
fn inline_cache() -> &'static Mutex<HashMap<u64, Weak<LoadedModel>>> {
    static CACHE: OnceLock<Mutex<HashMap<u64, Weak<LoadedModel>>>> = OnceLock::new();
    CACHE.get_or_init(Default::default)
}

fn inline(data: &MeshDataJson) -> std::result::Result<Arc<LoadedModel>, String> {
    let mut hasher = std::collections::hash_map::DefaultHasher::new();
    for p in &data.positions {
        p.map(f64::to_bits).hash(&mut hasher);
    }
    data.triangles.hash(&mut hasher);
    data.normals
        .as_ref()
        .map(|n| n.iter().map(|v| v.map(f64::to_bits)).collect::<Vec<_>>())
        .hash(&mut hasher);
    let key = hasher.finish();
    if let Some(hit) = inline_cache()
        .lock()
        .ok()
        .and_then(|c| c.get(&key).and_then(Weak::upgrade))
    {
        return Ok(hit);
    }
    let to_f32 = |what: &str, v: &[[f64; 3]]| -> std::result::Result<Vec<[f32; 3]>, String> {
        v.iter()
            .enumerate()
            .map(|(i, p)| {
                if p.iter()
                    .all(|x| x.is_finite() && x.abs() <= super::MAX_COORDINATE)
                {
                    Ok(p.map(|x| x as f32))
                } else {
                    Err(format!(
                        "{what}[{i}]: must be finite numbers within +-{:e}",
                        super::MAX_COORDINATE
                    ))
                }
            })
            .collect()
    };
    let positions = to_f32("positions", &data.positions)?;
    let normals = match &data.normals {
        Some(n) => {
            let n = to_f32("normals", n)?;
            let unit = n
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                    if l > 0.0 && l.is_finite() {
                        Ok(v.map(|x| x / l))
                    } else {
                        Err(format!("normals[{i}]: must not be the zero vector"))
                    }
                })
                .collect::<std::result::Result<Vec<_>, _>>()?;
            Some(unit)
        }
        None => None,
    };
    let mesh = MeshData {
        name: "data".into(),
        positions,
        normals,
        triangles: data.triangles.clone(),
        materials: Vec::new(),
        ..MeshData::default()
    };
    let loaded = Arc::new(
        LoadedModel::new(
            "data",
            vec![mesh],
            Vec::new(),
            vec![(0, DAffine3::IDENTITY)],
            None,
            Vec::new(),
        )
        .map_err(|e| e.trim_start_matches("data: mesh 'data': ").to_owned())?,
    );
    if let Ok(mut cache) = inline_cache().lock() {
        cache.retain(|_, w| w.strong_count() > 0);
        cache.insert(key, Arc::downgrade(&loaded));
    }
    Ok(loaded)
}
