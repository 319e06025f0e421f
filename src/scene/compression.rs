//! Compressed glTF geometry: `EXT_meshopt_compression` buffer views (the `meshopt` crate's
//! decoders and filters) and `KHR_draco_mesh_compression` primitives (the pure-Rust
//! `draco-core` decoder).

use super::accessor::{BufferData, DracoPrimitive};
use draco_core::draco_types::DataType;
use draco_core::geometry_indices::PointIndex;
use serde_json::Value;
use std::collections::HashMap;

/// The largest decoded size of one compressed buffer view or Draco primitive (bytes).
pub const MAX_DECODED_BYTES: u64 = 1 << 30;

const MESHOPT: &str = "EXT_meshopt_compression";
const DRACO: &str = "KHR_draco_mesh_compression";

/// Whether buffer `index` is an `EXT_meshopt_compression` fallback buffer, which need not
/// exist: every view into it is decoded from compressed data.
pub fn is_meshopt_fallback(root: &gltf::json::Root, index: usize) -> bool {
    root.buffers
        .get(index)
        .and_then(|b| b.extensions.as_ref())
        .and_then(|e| e.others.get(MESHOPT))
        .and_then(|m| m.get("fallback"))
        .and_then(Value::as_bool)
        .unwrap_or(false)
}

/// Decodes every `EXT_meshopt_compression` buffer view; returns the decoded bytes by view
/// index.
pub fn decode_meshopt_views(
    root: &gltf::json::Root,
    buffers: &[&[u8]],
) -> Result<HashMap<usize, Vec<u8>>, String> {
    let mut out = HashMap::new();
    for (index, view) in root.buffer_views.iter().enumerate() {
        let Some(ext) = view.extensions.as_ref().and_then(|e| e.others.get(MESHOPT)) else {
            continue;
        };
        let path = format!("bufferViews[{index}].extensions.{MESHOPT}");
        let bytes = decode_meshopt_view(ext, buffers, &path)?;
        if bytes.len() as u64 > view.byte_length.0 {
            return Err(format!(
                "{path}: {} decoded bytes exceed the view's byteLength {}",
                bytes.len(),
                view.byte_length.0
            ));
        }
        out.insert(index, bytes);
    }
    Ok(out)
}

fn decode_meshopt_view(ext: &Value, buffers: &[&[u8]], path: &str) -> Result<Vec<u8>, String> {
    let uint = |key: &str| ext.get(key).and_then(Value::as_u64);
    let text = |key: &str| ext.get(key).and_then(Value::as_str);
    let need = |key: &str| uint(key).ok_or_else(|| format!("{path}.{key} is missing"));
    let buffer = need("buffer")?;
    let offset = uint("byteOffset").unwrap_or(0);
    let length = need("byteLength")?;
    let stride = need("byteStride")?;
    let count = need("count")?;
    let data = buffers
        .get(buffer as usize)
        .ok_or_else(|| format!("{path}.buffer: buffers[{buffer}] does not exist"))?;
    let encoded = offset
        .checked_add(length)
        .filter(|&end| end <= data.len() as u64)
        .map(|end| &data[offset as usize..end as usize])
        .ok_or_else(|| {
            format!(
                "{path}: bytes {offset}..+{length} lie outside buffers[{buffer}] ({} bytes)",
                data.len()
            )
        })?;
    let decoded = count.saturating_mul(stride);
    if decoded > MAX_DECODED_BYTES {
        return Err(format!(
            "{path}: {count} × {stride} decoded bytes exceed the limit of {MAX_DECODED_BYTES}"
        ));
    }
    let count = count as usize;
    let fail = |e: meshopt::Error| format!("{path}: cannot decode: {e}");
    let mut bytes = match text("mode") {
        Some("ATTRIBUTES") => {
            if stride == 0 || stride % 4 != 0 || stride > 256 {
                return Err(format!(
                    "{path}.byteStride {stride} is not a multiple of 4 up to 256"
                ));
            }
            decode_vertices(encoded, count, stride as usize / 4).map_err(fail)?
        }
        Some(mode @ ("TRIANGLES" | "INDICES")) => {
            let triangles = mode == "TRIANGLES";
            match stride {
                2 => {
                    let v: Vec<u16> = if triangles {
                        meshopt::decode_index_buffer(encoded, count).map_err(fail)?
                    } else {
                        meshopt::decode_index_sequence(encoded, count).map_err(fail)?
                    };
                    v.iter().flat_map(|i| i.to_le_bytes()).collect()
                }
                4 => {
                    let v: Vec<u32> = if triangles {
                        meshopt::decode_index_buffer(encoded, count).map_err(fail)?
                    } else {
                        meshopt::decode_index_sequence(encoded, count).map_err(fail)?
                    };
                    v.iter().flat_map(|i| i.to_le_bytes()).collect()
                }
                _ => {
                    return Err(format!(
                        "{path}.byteStride {stride} is not 2 or 4 for {mode}"
                    ));
                }
            }
        }
        other => return Err(format!("{path}.mode {other:?} is not a meshopt mode")),
    };
    apply_filter(
        &mut bytes,
        text("filter").unwrap_or("NONE"),
        stride as usize,
        path,
    )?;
    Ok(bytes)
}

/// `decode_vertex_buffer` with a vertex of `words` 32-bit words, as little-endian bytes.
fn decode_vertices(encoded: &[u8], count: usize, words: usize) -> meshopt::Result<Vec<u8>> {
    /// One vertex of `K` words (`Default` for any `K`, unlike arrays longer than 32).
    #[derive(Clone, Copy)]
    #[repr(transparent)]
    struct Vertex<const K: usize>([u32; K]);
    impl<const K: usize> Default for Vertex<K> {
        fn default() -> Self {
            Self([0; K])
        }
    }
    fn run<const K: usize>(encoded: &[u8], count: usize) -> meshopt::Result<Vec<u8>> {
        Ok(meshopt::decode_vertex_buffer::<Vertex<K>>(encoded, count)?
            .iter()
            .flat_map(|v| v.0.iter().flat_map(|w| w.to_le_bytes()))
            .collect())
    }
    macro_rules! dispatch {
        ($($k:literal)*) => {
            match words {
                $($k => run::<$k>(encoded, count),)*
                _ => unreachable!("stride checked to be 4..=256"),
            }
        };
    }
    dispatch!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30
        31 32 33 34 35 36 37 38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59
        60 61 62 63 64)
}

/// Applies a meshopt filter in place to decoded vertices of `stride` bytes.
fn apply_filter(bytes: &mut [u8], filter: &str, stride: usize, path: &str) -> Result<(), String> {
    let bad = || format!("{path}: filter {filter} does not fit byteStride {stride}");
    match (filter, stride) {
        ("NONE", _) => {}
        ("OCTAHEDRAL", 4) => {
            let mut v: Vec<[i8; 4]> = chunks(bytes, |c| c.map(|b| b as i8));
            meshopt::decode_filter_oct(&mut v);
            write_back(bytes, v.iter().flat_map(|e| e.map(|c| c as u8)));
        }
        (f @ ("OCTAHEDRAL" | "QUATERNION"), 8) => {
            let mut v: Vec<[i16; 4]> = chunks(bytes, i16x4);
            if f == "OCTAHEDRAL" {
                meshopt::decode_filter_oct(&mut v);
            } else {
                meshopt::decode_filter_quat(&mut v);
            }
            write_back(bytes, le16(v.iter().map(|e| e.map(|c| c as u16))));
        }
        ("COLOR", 4) => {
            let mut v: Vec<[u8; 4]> = chunks(bytes, |c| c);
            meshopt::decode_filter_color(&mut v);
            write_back(bytes, v.into_iter().flatten());
        }
        ("COLOR", 8) => {
            let mut v: Vec<[u16; 4]> = chunks(bytes, |c| i16x4(c).map(|v| v as u16));
            meshopt::decode_filter_color(&mut v);
            write_back(bytes, le16(v.into_iter()));
        }
        ("EXPONENTIAL", s) if s % 4 == 0 => {
            let mut v: Vec<[u32; 1]> = bytes
                .chunks_exact(4)
                .map(|c| [u32::from_le_bytes([c[0], c[1], c[2], c[3]])])
                .collect();
            meshopt::decode_filter_exp(&mut v);
            write_back(bytes, v.iter().flat_map(|e| e[0].to_le_bytes()));
        }
        ("OCTAHEDRAL" | "QUATERNION" | "COLOR" | "EXPONENTIAL", _) => return Err(bad()),
        _ => return Err(format!("{path}.filter {filter} is not a meshopt filter")),
    }
    Ok(())
}

fn i16x4(c: [u8; 8]) -> [i16; 4] {
    [0, 1, 2, 3].map(|i| i16::from_le_bytes([c[2 * i], c[2 * i + 1]]))
}

/// Little-endian bytes of 16-bit quadruples.
fn le16(v: impl Iterator<Item = [u16; 4]>) -> impl Iterator<Item = u8> {
    v.flat_map(|e| e.into_iter().flat_map(u16::to_le_bytes))
}

fn chunks<const B: usize, T>(bytes: &[u8], f: impl Fn([u8; B]) -> T) -> Vec<T> {
    bytes
        .chunks_exact(B)
        .map(|c| f(std::array::from_fn(|i| c[i])))
        .collect()
}

fn write_back(bytes: &mut [u8], values: impl Iterator<Item = u8>) {
    for (dst, src) in bytes.iter_mut().zip(values) {
        *dst = src;
    }
}

/// Decodes the Draco data of primitive `path` (`meshes[m].primitives[p]`) whose extension
/// object is `ext`.
pub fn decode_draco(
    root: &gltf::json::Root,
    data: &BufferData,
    primitive: &gltf::json::mesh::Primitive,
    path: &str,
) -> Result<Option<DracoPrimitive>, String> {
    let Some(ext) = primitive
        .extensions
        .as_ref()
        .and_then(|e| e.others.get(DRACO))
    else {
        return Ok(None);
    };
    let path = format!("{path}.extensions.{DRACO}");
    let view = ext
        .get("bufferView")
        .and_then(Value::as_u64)
        .ok_or_else(|| format!("{path}.bufferView is missing"))?;
    let (bytes, _) = data.view(root, view as usize)?;
    let mut buffer = draco_core::decoder_buffer::DecoderBuffer::new(bytes);
    let mut mesh = draco_core::mesh::Mesh::new();
    draco_core::mesh_decoder::MeshDecoder::new()
        .decode(&mut buffer, &mut mesh)
        .map_err(|e| format!("{path}: cannot decode: {e}"))?;
    let points = mesh.num_points();
    if points as u64 > MAX_DECODED_BYTES / 16 {
        return Err(format!(
            "{path}: {points} points exceed the limit of {}",
            MAX_DECODED_BYTES / 16
        ));
    }
    let indices: Vec<u32> = (0..mesh.num_faces())
        .flat_map(|f| mesh.face(draco_core::geometry_indices::FaceIndex(f as u32)))
        .map(|p| p.0)
        .collect();
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= points) {
        return Err(format!(
            "{path}: index {bad} is out of range ({points} points)"
        ));
    }
    let mut attributes = HashMap::new();
    let Some(map) = ext.get("attributes").and_then(Value::as_object) else {
        return Err(format!("{path}.attributes is missing"));
    };
    for (semantic, id) in map {
        let id = id
            .as_u64()
            .ok_or_else(|| format!("{path}.attributes.{semantic} is not an id"))?;
        let attribute = mesh.attribute_by_unique_id(id as u32).ok_or_else(|| {
            format!("{path}.attributes.{semantic}: the Draco data has no attribute {id}")
        })?;
        let normalized = primitive
            .attributes
            .iter()
            .find(|(k, _)| semantic_name(k).as_deref() == Some(semantic.as_str()))
            .and_then(|(_, a)| root.accessors.get(a.value()))
            .is_some_and(|a| a.normalized);
        let components = (attribute.num_components() as usize).min(4);
        let stride = attribute.byte_stride().max(0) as usize;
        let raw = attribute.buffer().data();
        let data_type = attribute.data_type();
        let size = data_type.byte_length();
        let values: Result<Vec<[f32; 4]>, String> = (0..points)
            .map(|p| {
                let at = attribute.mapped_index(PointIndex(p as u32)).0 as usize * stride;
                let mut out = [0.0; 4];
                for (c, lane) in out.iter_mut().enumerate().take(components) {
                    let bytes = raw.get(at + c * size..at + (c + 1) * size).ok_or_else(|| {
                        format!("{path}.attributes.{semantic}: point {p} lies outside its data")
                    })?;
                    *lane = draco_value(data_type, bytes, normalized);
                }
                Ok(out)
            })
            .collect();
        attributes.insert(semantic.clone(), values?);
    }
    Ok(Some(DracoPrimitive {
        indices,
        attributes,
    }))
}

/// A warning when the primitive's accessors declare counts other than its decoded Draco data
/// holds (the specification requires them equal); the decoded data is used.
pub fn draco_count_mismatch(
    root: &gltf::json::Root,
    primitive: &gltf::json::mesh::Primitive,
    draco: &DracoPrimitive,
    path: &str,
) -> Option<String> {
    let count = |a: usize| root.accessors.get(a).map(|a| a.count.0);
    let points = draco.attributes.values().next().map_or(0, Vec::len) as u64;
    let mut problems = Vec::new();
    if let Some(declared) = primitive.indices.as_ref().and_then(|i| count(i.value()))
        && declared != draco.indices.len() as u64
    {
        problems.push(format!(
            "indices declare {declared}, the Draco data has {}",
            draco.indices.len()
        ));
    }
    for (semantic, accessor) in &primitive.attributes {
        if let (Some(name), Some(declared)) = (semantic_name(semantic), count(accessor.value()))
            && draco.attributes.contains_key(&name)
            && declared != points
        {
            problems.push(format!(
                "{name} declares {declared}, the Draco data has {points}"
            ));
        }
    }
    (!problems.is_empty()).then(|| {
        format!(
            "{path}: accessor counts disagree with the decoded mesh ({}); the decoded mesh is used",
            problems.join(", ")
        )
    })
}

/// The glTF name of an attribute semantic (`POSITION`, `TEXCOORD_0` …).
fn semantic_name(
    s: &gltf::json::validation::Checked<gltf::json::mesh::Semantic>,
) -> Option<String> {
    match s {
        gltf::json::validation::Checked::Valid(s) => Some(s.to_string()),
        gltf::json::validation::Checked::Invalid => None,
    }
}

fn draco_value(t: DataType, b: &[u8], normalized: bool) -> f32 {
    let scale = |v: f32, max: f32| if normalized { (v / max).max(-1.0) } else { v };
    match t {
        DataType::Int8 => scale(b[0] as i8 as f32, 127.0),
        DataType::Uint8 | DataType::Bool => scale(b[0] as f32, 255.0),
        DataType::Int16 => scale(i16::from_le_bytes([b[0], b[1]]) as f32, 32767.0),
        DataType::Uint16 => scale(u16::from_le_bytes([b[0], b[1]]) as f32, 65535.0),
        DataType::Int32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        DataType::Uint32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
        DataType::Float32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        DataType::Float64 => f64::from_le_bytes(std::array::from_fn(|i| b[i])) as f32,
        DataType::Int64 => i64::from_le_bytes(std::array::from_fn(|i| b[i])) as f32,
        DataType::Uint64 => u64::from_le_bytes(std::array::from_fn(|i| b[i])) as f32,
        DataType::Invalid => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// Accessor counts are compared with the decoded Draco data: a disagreement is one
    /// warning naming each accessor, agreement none.
    #[test]
    fn draco_accessor_counts_that_disagree_are_one_warning() {
        let root: gltf::json::Root = serde_json::from_value(json!({
            "asset": {"version": "2.0"},
            "accessors": [
                {"componentType": 5126, "count": 4, "type": "VEC3"},
                {"componentType": 5125, "count": 6, "type": "SCALAR"},
                {"componentType": 5126, "count": 3, "type": "VEC2"}
            ],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 2}, "indices": 1}]}]
        }))
        .unwrap();
        let primitive = &root.meshes[0].primitives[0];
        let decoded = |points: usize, corners: usize| DracoPrimitive {
            indices: vec![0; corners],
            attributes: ["POSITION", "TEXCOORD_0"]
                .into_iter()
                .map(|s| (s.to_string(), vec![[0.0; 4]; points]))
                .collect(),
        };
        let w = draco_count_mismatch(&root, primitive, &decoded(4, 3), "p").unwrap();
        assert!(
            w.starts_with("p: ")
                && w.contains("indices declare 6, the Draco data has 3")
                && w.contains("TEXCOORD_0 declares 3, the Draco data has 4")
                && !w.contains("POSITION"),
            "{w}"
        );
        let root: gltf::json::Root = {
            let mut v = serde_json::to_value(&root).unwrap();
            v["accessors"][2]["count"] = json!(4);
            serde_json::from_value(v).unwrap()
        };
        let primitive = &root.meshes[0].primitives[0];
        assert_eq!(
            draco_count_mismatch(&root, primitive, &decoded(4, 6), "p"),
            None
        );
    }

    #[test]
    fn meshopt_attributes_and_octahedral_filter_round_trip() {
        // Three 12-byte vertices, encoded by meshoptimizer's own encoder.
        let vertices: Vec<[f32; 3]> = vec![[0.0, 1.0, 2.0], [-3.5, 4.25, 1e3], [7.0, -8.0, 0.5]];
        let encoded = meshopt::encode_vertex_buffer(&vertices).unwrap();
        let ext = json!({"buffer": 0, "byteLength": encoded.len(), "byteStride": 12,
                         "count": 3, "mode": "ATTRIBUTES"});
        let bytes = decode_meshopt_view(&ext, &[&encoded], "v").unwrap();
        let floats: Vec<f32> = bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        assert_eq!(floats, vertices.concat());

        // Unit normals through the octahedral filter (16-bit) come back within 1e-3.
        let normals = [[0.0, 0.0, 1.0, 0.0], [0.6, -0.8, 0.0, 0.0]];
        let filtered = meshopt::encode_filter_oct::<i16>(&normals, 16);
        let encoded = meshopt::encode_vertex_buffer(&filtered).unwrap();
        let ext = json!({"buffer": 0, "byteLength": encoded.len(), "byteStride": 8,
                         "count": 2, "mode": "ATTRIBUTES", "filter": "OCTAHEDRAL"});
        let bytes = decode_meshopt_view(&ext, &[&encoded], "v").unwrap();
        for (k, n) in normals.iter().enumerate() {
            for c in 0..3 {
                let v = i16::from_le_bytes([bytes[8 * k + 2 * c], bytes[8 * k + 2 * c + 1]]);
                assert!((v as f32 / 32767.0 - n[c]).abs() < 1e-3, "{k} {c}: {v}");
            }
        }

        // Truncated data and a bad filter are errors naming the element.
        let e = decode_meshopt_view(&ext, &[&encoded[..4]], "bufferViews[2]").unwrap_err();
        assert!(e.starts_with("bufferViews[2]"), "{e}");
        let bad = json!({"buffer": 0, "byteLength": encoded.len(), "byteStride": 8,
                         "count": 2, "mode": "ATTRIBUTES", "filter": "QUATERNION4"});
        assert!(decode_meshopt_view(&bad, &[&encoded], "v").is_err());
    }

    #[test]
    fn meshopt_indices_round_trip() {
        let indices: Vec<u32> = vec![0, 1, 2, 2, 1, 3];
        let encoded = meshopt::encode_index_buffer(&indices, 4).unwrap();
        let ext = json!({"buffer": 0, "byteLength": encoded.len(), "byteStride": 2,
                         "count": 6, "mode": "TRIANGLES"});
        let bytes = decode_meshopt_view(&ext, &[&encoded], "i").unwrap();
        let back: Vec<u32> = bytes
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]) as u32)
            .collect();
        assert_eq!(back, indices);
    }
}
