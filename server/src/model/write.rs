//! Meshes saved as files (for tests and benchmarks: generated or converted
//! meshes that [`super::load_file`] reads back exactly).

use super::MeshData;
use std::io::{self, Write};

/// Writes `mesh` as binary little-endian PLY: `x y z` floats (and
/// `nx ny nz` when the mesh has normals), faces as `uchar`-counted `int`
/// `vertex_indices` lists. Materials are not written (PLY has none).
pub fn write_ply_binary(mesh: &MeshData, out: &mut impl Write) -> io::Result<()> {
    let normals = mesh
        .normals
        .as_deref()
        .filter(|n| n.len() == mesh.positions.len());
    let mut w = io::BufWriter::new(out);
    writeln!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment written by pathstream"
    )?;
    writeln!(w, "element vertex {}", mesh.positions.len())?;
    writeln!(w, "property float x\nproperty float y\nproperty float z")?;
    if normals.is_some() {
        writeln!(w, "property float nx\nproperty float ny\nproperty float nz")?;
    }
    writeln!(w, "element face {}", mesh.triangles.len())?;
    writeln!(w, "property list uchar int vertex_indices\nend_header")?;
    for (i, p) in mesh.positions.iter().enumerate() {
        for x in p {
            w.write_all(&x.to_le_bytes())?;
        }
        if let Some(n) = normals.and_then(|n| n.get(i)) {
            for x in n {
                w.write_all(&x.to_le_bytes())?;
            }
        }
    }
    for t in &mesh.triangles {
        w.write_all(&[3])?;
        for &i in t {
            let i = i32::try_from(i).map_err(|_| {
                io::Error::new(io::ErrorKind::InvalidInput, "vertex index over i32::MAX")
            })?;
            w.write_all(&i.to_le_bytes())?;
        }
    }
    w.flush()
}

/// Writes `mesh` as OBJ text: `v` lines, `vn` lines when the mesh has
/// normals, and `f v//vn` (or `f v`) triangles. Floats are written in their
/// shortest round-trip form, so they read back bit for bit. Materials are
/// not written (no MTL).
pub fn write_obj(mesh: &MeshData, out: &mut impl Write) -> io::Result<()> {
    let normals = mesh
        .normals
        .as_deref()
        .filter(|n| n.len() == mesh.positions.len());
    let mut w = io::BufWriter::new(out);
    writeln!(w, "# written by pathstream\no {}", mesh.name)?;
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p[0], p[1], p[2])?;
    }
    for n in normals.unwrap_or_default() {
        writeln!(w, "vn {} {} {}", n[0], n[1], n[2])?;
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| u64::from(i) + 1);
        if normals.is_some() {
            writeln!(w, "f {a}//{a} {b}//{b} {c}//{c}")?;
        } else {
            writeln!(w, "f {a} {b} {c}")?;
        }
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{load_bytes, Limits};

    fn mesh() -> MeshData {
        MeshData {
            name: "quad".into(),
            positions: vec![
                [0.1, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 1e-7],
                [0.0, 1.0, -3.5],
            ],
            normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            materials: vec![0, 0],
            ..MeshData::default()
        }
    }

    #[test]
    fn written_files_read_back_exactly() {
        let m = mesh();
        for (name, write) in [
            (
                "quad.ply",
                write_ply_binary as fn(&MeshData, &mut Vec<u8>) -> io::Result<()>,
            ),
            ("quad.obj", write_obj),
        ] {
            let mut bytes = Vec::new();
            write(&m, &mut bytes).expect("writes");
            let back = load_bytes(&bytes, name, &Limits::default()).expect("reads back");
            assert_eq!(back.meshes, vec![m.clone()], "{name}");
            let mut flat = m.clone();
            flat.normals = None;
            bytes.clear();
            write(&flat, &mut bytes).expect("writes");
            let back = load_bytes(&bytes, name, &Limits::default()).expect("reads back");
            assert_eq!(back.meshes, vec![flat], "{name}");
        }
    }
}
