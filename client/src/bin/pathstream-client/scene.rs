//! What `--scene` names: a built-in scene, a scene JSON file (its model
//! files, environment map and material textures uploaded first), or a
//! model file uploaded and placed whole.

use super::{usage, Failure};
use pathstream_client::wire::asset::{is_environment_name, is_model_name};
use pathstream_client::{Client, ClientError, SceneSpec};
use std::path::Path;

/// Uploads a model file; prints what the server says it does not render.
pub async fn upload(client: &Client, path: &Path, what: &str) -> Result<String, Failure> {
    let bytes = std::fs::read(path)
        .map_err(|e| usage(format!("{what}: cannot read {}: {e}", path.display())))?;
    let name = path
        .file_name()
        .map_or_else(|| "model".into(), |n| n.to_string_lossy().into_owned());
    let asset = client
        .upload_asset(&name, bytes)
        .await
        .map_err(|e| match e {
            ClientError::Server {
                status: 400 | 413 | 415,
                message,
            } => usage(format!("{what}: {message}")),
            e => Failure::from(e),
        })?;
    for w in &asset.asset.warnings {
        eprintln!("warning: {name}: {w}");
    }
    Ok(asset.asset.id)
}

/// The scene to send: a built-in name; a scene JSON file, whose `file`
/// references (relative to it) are uploaded and named by asset; or a model
/// file (.obj, .gltf, .glb, .ply), uploaded and placed whole (framed and
/// lit by the server's defaults).
pub async fn scene_spec(client: &Client, scene: &str) -> Result<SceneSpec, Failure> {
    let path = Path::new(scene);
    if is_model_name(scene) && path.is_file() {
        let id = upload(client, path, &format!("--scene {scene}")).await?;
        return Ok(SceneSpec::Json(
            serde_json::json!({"objects": [{"type": "model", "asset": id}]}),
        ));
    }
    if !(scene.ends_with(".json") || path.is_file()) {
        return Ok(SceneSpec::Name(scene.to_owned()));
    }
    let text = std::fs::read_to_string(path).map_err(|e| usage(format!("--scene {scene}: {e}")))?;
    let mut json: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| usage(format!("--scene {scene}: not JSON: {e}")))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    // An environment map file: uploaded, named by asset.
    let map = json.pointer("/environment/map").and_then(|m| m.as_str());
    if let Some(file) = map.filter(|m| is_environment_name(m)).map(str::to_owned) {
        let id = upload(
            client,
            &dir.join(&file),
            &format!("--scene {scene}: environment.map"),
        )
        .await?;
        json["environment"]["map"] = serde_json::Value::String(id);
    }
    if let Some(objects) = json.get_mut("objects").and_then(|o| o.as_array_mut()) {
        for (i, o) in objects.iter_mut().enumerate() {
            let Some(file) = o.get("file").and_then(|f| f.as_str()).map(str::to_owned) else {
                continue;
            };
            let id = upload(
                client,
                &dir.join(&file),
                &format!("--scene {scene}: objects[{i}].file"),
            )
            .await?;
            if let Some(map) = o.as_object_mut() {
                map.remove("file");
                map.insert("asset".into(), serde_json::Value::String(id));
            }
        }
    }
    // Material textures named by file: uploaded, named by asset.
    if let Some(materials) = json.get_mut("materials").and_then(|m| m.as_object_mut()) {
        for (name, m) in materials.iter_mut() {
            for field in TEXTURED_FIELDS {
                let slot = m.get_mut(field).and_then(|f| f.as_object_mut());
                let Some(slot) = slot else { continue };
                let Some(file) = slot.get("texture").and_then(|t| t.as_str()) else {
                    continue;
                };
                if is_asset_id(file) {
                    continue;
                }
                let what = format!("--scene {scene}: materials.{name}.{field}.texture");
                let id = upload(client, &dir.join(file), &what).await?;
                slot.insert("texture".into(), serde_json::Value::String(id));
            }
        }
    }
    Ok(SceneSpec::Json(json))
}

/// The material fields that may name a texture.
const TEXTURED_FIELDS: [&str; 6] = [
    "albedo",
    "base_color",
    "metallic",
    "roughness",
    "emission",
    "normal",
];

/// Whether `name` is an asset id (a SHA-256 in hex) rather than a file.
fn is_asset_id(name: &str) -> bool {
    name.len() == 64 && name.bytes().all(|b| b.is_ascii_hexdigit())
}
