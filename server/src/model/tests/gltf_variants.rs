//! glTF: malformed and unusual variants of a one-triangle GLB (quantized
//! attributes, broken accessors and views, features that are warned of).

use super::assert_guarantees;
use super::gltf::{pbr, TRI};
use super::untextured;
use crate::model::write_glb::pack as glb;
use crate::model::{load_bytes, Limits, Model};
use serde_json::{json, Value};

/// A one-triangle GLB: u16 positions and i8 normalised normals
/// (KHR_mesh_quantization), u16 indices; `edit` changes it first.
fn mini(edit: impl FnOnce(&mut Value, &mut Vec<u8>)) -> Result<Model, String> {
    let mut bin: Vec<u8> = [[0u16, 0, 0], [1, 0, 0], [0, 1, 0]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    bin.extend([0i8, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0].map(|x| x as u8));
    bin.extend([0u16, 1, 2, 0].iter().flat_map(|x| x.to_le_bytes()));
    let mut doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5123, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5120, "normalized": true, "count": 3, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteLength": 18},
            {"buffer": 0, "byteOffset": 18, "byteLength": 12, "byteStride": 4},
            {"buffer": 0, "byteOffset": 30, "byteLength": 6}
        ],
        "buffers": [{"byteLength": 38}]
    });
    edit(&mut doc, &mut bin);
    load_bytes(&glb(&doc, &bin), "m.glb", &Limits::default()).map_err(|e| e.to_string())
}

#[test]
fn quantized_attributes_and_no_scene() {
    let m = mini(|_, _| {}).expect("loads");
    assert_guarantees(&m);
    assert_eq!(m.meshes[0].positions, TRI.to_vec());
    assert_eq!(m.meshes[0].normals, Some(vec![[0.0, 0.0, 1.0]; 3]));
    assert_eq!(m.meshes[0].triangles, vec![[0, 1, 2]]);
    assert_eq!(m.camera, None);
    let m = mini(|d, _| {
        if let Some(o) = d.as_object_mut() {
            o.remove("scenes");
        }
    })
    .expect("loads");
    assert_eq!(m.instances.len(), 1);
    assert_eq!(
        m.warnings,
        [
            "no scene: every root node is placed",
            "primitives without a material use the glTF default material: white diffuse (albedo 1)"
        ]
    );
}

#[test]
fn malformed_gltf_errors_name_the_problem() {
    let nan = mini(|d, bin| {
        d["accessors"][0]["componentType"] = json!(5126);
        d["bufferViews"][0]["byteLength"] = json!(36);
        d["bufferViews"][1]["byteOffset"] = json!(36);
        d["bufferViews"][2]["byteOffset"] = json!(48);
        d["buffers"][0]["byteLength"] = json!(56);
        let mut floats: Vec<u8> = [0.0f32, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 1.0, 0.0]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        floats.extend(&bin[18..]);
        *bin = floats;
    });
    assert_eq!(
        nan,
        Err("m.glb: meshes[0].primitives[0]: vertex 1: position [NaN, 0, 0] is not finite".into())
    );
    type Edit = Box<dyn FnOnce(&mut Value, &mut Vec<u8>)>;
    let cases: Vec<(Edit, &str)> = vec![
        (Box::new(|_, bin| bin[32] = 7), "m.glb: meshes[0].primitives[0]: triangle 0: vertex index 7 out of range (3 vertices)"),
        (Box::new(|d, _| d["meshes"][0]["primitives"][0]["mode"] = json!(0)), "m.glb: no triangles"),
        (
            Box::new(|d, _| d["accessors"][0]["count"] = json!(4_000_000_000u64)),
            "m.glb: meshes[0].primitives[0]: 4000000000 vertices, more than the limit of 16000000",
        ),
        (
            Box::new(|d, _| d["accessors"][0]["count"] = json!(1000)),
            "m.glb: meshes[0].primitives[0].attributes.POSITION: 1000 elements of 6 bytes from byte 0 do not fit in bufferViews[0] (18 bytes)",
        ),
        (
            Box::new(|d, _| d["buffers"][0]["byteLength"] = json!(1000)),
            "m.glb: buffers[0]: holds 40 bytes, but its byteLength is 1000 (truncated)",
        ),
        (Box::new(|d, _| d["nodes"][0]["mesh"] = json!(5)), "m.glb: nodes[0].mesh: index out of range"),
        (
            Box::new(|d, _| d["nodes"] = json!([{"children": [1]}, {"mesh": 0, "children": [0]}])),
            "m.glb: nodes[0]: is reached twice in the scene's node hierarchy (a cycle, or a node with two parents)",
        ),
        (
            Box::new(|d, _| d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"])),
            "m.glb: extensionsRequired: KHR_draco_mesh_compression (compressed geometry) is not supported",
        ),
        (
            Box::new(|d, _| d["accessors"][2]["componentType"] = json!(5126)),
            "m.glb: meshes[0].primitives[0].indices: accessors[2] is Scalar of F32, not unsigned integer indices",
        ),
    ];
    for (edit, want) in cases {
        assert_eq!(mini(edit).err().as_deref(), Some(want));
    }
    let e = load_bytes(
        b"{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [",
        "m.gltf",
        &Limits::default(),
    )
    .expect_err("json");
    assert_eq!(
        e.to_string(),
        "m.gltf: JSON line 1, column 40: EOF while parsing a list"
    );
}

#[test]
fn animation_skins_morph_targets_and_maps_are_warned_and_colours_read() {
    let m = mini(|d, _| {
        d["animations"] = json!([{"channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                                  "samplers": [{"input": 2, "output": 0}]}]);
        d["skins"] = json!([{"joints": [0]}]);
        d["nodes"][0]["skin"] = json!(0);
        d["meshes"][0]["weights"] = json!([0.5]);
        let prim = &mut d["meshes"][0]["primitives"][0];
        prim["targets"] = json!([{"POSITION": 0}]);
        prim["attributes"]["COLOR_0"] = json!(1);
        prim["material"] = json!(0);
        d["materials"] = json!([{"occlusionTexture": {"index": 0}, "alphaMode": "MASK", "alphaCutoff": 0.25}]);
        d["textures"] = json!([{"source": 0}]);
        d["images"] = json!([{"uri": "x.png"}]);
    })
    .expect("loads");
    assert_guarantees(&m);
    // COLOR_0 (here the normals' accessor) is read as the vertex colours.
    assert!(m.meshes[0].colors.is_some());
    assert_eq!(
        m.materials,
        untextured([("material0", pbr([1.0; 3], 1.0, 1.0))])
    );
    assert_eq!(
        m.warnings,
        [
            "1 animations ignored (the scene is read at rest)",
            "skins ignored (skinned meshes are placed by their node's transform)",
            "mesh \"mesh0\": morph targets ignored (the base shape is used)",
            "occlusion maps are not used: a path tracer finds the occlusion itself",
        ]
    );
}
