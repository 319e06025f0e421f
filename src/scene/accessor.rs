//! Reading glTF accessors: every component type (float, and normalized or plain i8/u8/i16/
//! u16/u32), interleaved buffer views, sparse substitution, and buffer views decoded from
//! `EXT_meshopt_compression`. Every size the file implies is checked against the bytes that
//! exist before anything is allocated; an error names the element (`accessors[3]`).

use gltf::json::accessor::{ComponentType, Type};
use gltf::json::validation::Checked;
use std::collections::HashMap;

/// The most elements an accessor without a buffer view (zeros, then sparse values) may have.
pub const MAX_UNBACKED_ELEMENTS: u64 = 1 << 24;

/// The bytes accessors read from: the loaded buffers, and buffer views whose content was
/// decoded (meshopt) and replaces what their buffer holds.
pub struct BufferData<'a> {
    /// Buffer contents, by buffer index (empty for a meshopt fallback buffer).
    pub buffers: Vec<&'a [u8]>,
    /// Decoded content of compressed buffer views, by view index.
    pub decoded_views: HashMap<usize, Vec<u8>>,
}

impl BufferData<'_> {
    /// The bytes of buffer view `index` and its byte stride, with the view checked to lie
    /// within its buffer.
    pub fn view(
        &self,
        root: &gltf::json::Root,
        index: usize,
    ) -> Result<(&[u8], Option<usize>), String> {
        let path = format!("bufferViews[{index}]");
        let view = root
            .buffer_views
            .get(index)
            .ok_or_else(|| format!("{path} does not exist"))?;
        let stride = view.byte_stride.map(|s| s.0);
        if let Some(bytes) = self.decoded_views.get(&index) {
            return Ok((bytes.as_slice(), stride));
        }
        let buffer = view.buffer.value();
        let data = self
            .buffers
            .get(buffer)
            .ok_or_else(|| format!("{path}.buffer: buffers[{buffer}] does not exist"))?;
        let start = view.byte_offset.map_or(0, |o| o.0);
        let end = start.checked_add(view.byte_length.0);
        match end {
            Some(end) if end <= data.len() as u64 => {
                Ok((&data[start as usize..end as usize], stride))
            }
            _ => Err(format!(
                "{path}: bytes {start}..{} lie outside buffers[{buffer}] ({} bytes)",
                start.saturating_add(view.byte_length.0),
                data.len()
            )),
        }
    }
}

/// The layout of one accessor's elements.
#[derive(Clone, Copy)]
struct Layout {
    component: ComponentType,
    normalized: bool,
    /// Components per element (1 for SCALAR … 16 for MAT4).
    components: usize,
    /// Rows of a matrix column (columns of 1- and 2-byte components start 4-byte aligned).
    rows: usize,
}

impl Layout {
    fn component_size(&self) -> usize {
        match self.component {
            ComponentType::I8 | ComponentType::U8 => 1,
            ComponentType::I16 | ComponentType::U16 => 2,
            ComponentType::U32 | ComponentType::F32 => 4,
        }
    }

    /// Byte offset of component `c` within an element.
    fn component_offset(&self, c: usize) -> usize {
        let size = self.component_size();
        let column = (self.rows * size).next_multiple_of(4);
        if self.components > 4 {
            (c / self.rows) * column + (c % self.rows) * size
        } else {
            c * size
        }
    }

    /// Bytes one element occupies.
    fn element_size(&self) -> usize {
        if self.components > 4 {
            let columns = self.components / self.rows;
            columns * (self.rows * self.component_size()).next_multiple_of(4)
        } else {
            self.components * self.component_size()
        }
    }

    /// Component `c` of the element at `bytes` as a float (normalized integers mapped to
    /// [0, 1] or [-1, 1] as the glTF specification says).
    fn float(&self, bytes: &[u8], c: usize) -> f32 {
        let at = self.component_offset(c);
        let b = &bytes[at..];
        let n = self.normalized;
        match self.component {
            ComponentType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            ComponentType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
            ComponentType::I8 => {
                let v = b[0] as i8 as f32;
                if n { (v / 127.0).max(-1.0) } else { v }
            }
            ComponentType::U8 => {
                let v = b[0] as f32;
                if n { v / 255.0 } else { v }
            }
            ComponentType::I16 => {
                let v = i16::from_le_bytes([b[0], b[1]]) as f32;
                if n { (v / 32767.0).max(-1.0) } else { v }
            }
            ComponentType::U16 => {
                let v = u16::from_le_bytes([b[0], b[1]]) as f32;
                if n { v / 65535.0 } else { v }
            }
        }
    }

    /// Component `c` as an unsigned integer (indices and joints).
    fn uint(&self, bytes: &[u8], c: usize) -> u32 {
        let at = self.component_offset(c);
        let b = &bytes[at..];
        match self.component {
            ComponentType::U8 => b[0] as u32,
            ComponentType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
            ComponentType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            ComponentType::I8 => b[0] as i8 as u32,
            ComponentType::I16 => i16::from_le_bytes([b[0], b[1]]) as u32,
            ComponentType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as u32,
        }
    }
}

/// Reads accessor `index` as floats with `N` components per element. Elements with fewer
/// components than `N` are an error; extra components of the file are dropped only when
/// `N` is smaller than the accessor's width by design of the caller (e.g. VEC4 colors read
/// as 4, VEC3 colors read as 3).
pub fn read_floats<const N: usize>(
    root: &gltf::json::Root,
    data: &BufferData,
    index: usize,
) -> Result<Vec<[f32; N]>, String> {
    read(root, data, index, N, ComponentType::F32, |layout, bytes| {
        std::array::from_fn(|c| layout.float(bytes, c))
    })
}

/// Reads accessor `index` as unsigned integers with `N` components per element (indices,
/// joints). Float accessors are refused.
pub fn read_uints<const N: usize>(
    root: &gltf::json::Root,
    data: &BufferData,
    index: usize,
) -> Result<Vec<[u32; N]>, String> {
    if let Some(a) = root.accessors.get(index)
        && matches!(
            a.component_type,
            Checked::Valid(gltf::json::accessor::GenericComponentType(
                ComponentType::F32
            ))
        )
    {
        return Err(format!(
            "accessors[{index}].componentType: FLOAT where integers are required"
        ));
    }
    read(root, data, index, N, ComponentType::U32, |layout, bytes| {
        std::array::from_fn(|c| layout.uint(bytes, c))
    })
}

/// The bytes and stride of `count` elements of `layout` at `offset` in buffer view `view`,
/// checked to lie within the view.
fn elements<'a>(
    root: &gltf::json::Root,
    data: &'a BufferData,
    view: usize,
    offset: u64,
    count: u64,
    layout: &Layout,
    path: &str,
) -> Result<(&'a [u8], usize), String> {
    let (bytes, stride) = data.view(root, view)?;
    let size = layout.element_size();
    let stride = stride.unwrap_or(size);
    if stride < size {
        return Err(format!(
            "{path}: bufferViews[{view}].byteStride {stride} is smaller than an element ({size} bytes)"
        ));
    }
    // offset + stride × (count − 1) + element size must fit in the view.
    let need = count
        .checked_sub(1)
        .map(|last| {
            (stride as u64)
                .checked_mul(last)
                .and_then(|s| s.checked_add(offset))
                .and_then(|s| s.checked_add(size as u64))
        })
        .unwrap_or(Some(0));
    match need {
        Some(need) if need <= bytes.len() as u64 => {
            Ok((&bytes[offset.min(need) as usize..], stride))
        }
        _ => Err(format!(
            "{path}: {count} elements of {size} bytes every {stride} from byte {offset} overrun \
             bufferViews[{view}] ({} bytes)",
            bytes.len()
        )),
    }
}

/// The elements of an accessor of `want` components per element, each converted from its
/// bytes by `convert`; where the file holds exactly `[T; N]` (components of type `native`,
/// `T`'s own little-endian form, N to an element, tightly packed, no sparse values) the bytes
/// are copied as they are, at memory speed (a 64 M-triangle file's positions and indices:
/// most of its reading time went to converting element by element).
fn read<T: bytemuck::Pod + Default, const N: usize>(
    root: &gltf::json::Root,
    data: &BufferData,
    index: usize,
    want: usize,
    native: ComponentType,
    convert: impl Fn(&Layout, &[u8]) -> [T; N],
) -> Result<Vec<[T; N]>, String> {
    let path = format!("accessors[{index}]");
    let accessor = root
        .accessors
        .get(index)
        .ok_or_else(|| format!("{path} does not exist"))?;
    let Checked::Valid(component) = accessor.component_type else {
        return Err(format!(
            "{path}.componentType is not a valid component type"
        ));
    };
    let Checked::Valid(kind) = accessor.type_ else {
        return Err(format!("{path}.type is not a valid type"));
    };
    let components = kind.multiplicity();
    if components < want {
        return Err(format!(
            "{path}: {components} components per element where {want} are needed"
        ));
    }
    let layout = Layout {
        component: component.0,
        normalized: accessor.normalized,
        components,
        rows: match kind {
            Type::Mat2 => 2,
            Type::Mat3 => 3,
            Type::Mat4 => 4,
            _ => components,
        },
    };
    let count = accessor.count.0;
    let size = layout.element_size();

    // Without a buffer view the elements are zeros (then usually replaced by sparse values);
    // with one, the count is bounded by the view's bytes before allocating.
    let mut out: Vec<[T; N]> = match accessor.buffer_view {
        Some(view) => {
            let offset = accessor.byte_offset.map_or(0, |o| o.0);
            let (bytes, stride) =
                elements(root, data, view.value(), offset, count, &layout, &path)?;
            let packed = cfg!(target_endian = "little")
                && layout.component == native
                && components == N
                && components <= 4
                && stride == size
                && size == std::mem::size_of::<[T; N]>()
                && accessor.sparse.is_none();
            if packed {
                bytemuck::pod_collect_to_vec(&bytes[..count as usize * size])
            } else {
                (0..count as usize)
                    .map(|i| convert(&layout, &bytes[i * stride..i * stride + size]))
                    .collect()
            }
        }
        None => {
            // A view-less accessor allocates its count with no bytes to bound it.
            if count > MAX_UNBACKED_ELEMENTS {
                return Err(format!(
                    "{path}: {count} elements without a bufferView (limit {MAX_UNBACKED_ELEMENTS})"
                ));
            }
            vec![[T::default(); N]; count as usize]
        }
    };

    if let Some(sparse) = &accessor.sparse {
        let n = sparse.count.0;
        if n > count {
            return Err(format!(
                "{path}.sparse.count {n} exceeds the accessor's count {count}"
            ));
        }
        let Checked::Valid(index_type) = sparse.indices.component_type else {
            return Err(format!(
                "{path}.sparse.indices.componentType is not a valid index type"
            ));
        };
        let index_layout = Layout {
            component: index_type.0,
            normalized: false,
            components: 1,
            rows: 1,
        };
        let part = |view: usize, offset: u64, layout: &Layout, what: &str| {
            elements(
                root,
                data,
                view,
                offset,
                n,
                layout,
                &format!("{path}.sparse.{what}"),
            )
        };
        let (index_bytes, _) = part(
            sparse.indices.buffer_view.value(),
            sparse.indices.byte_offset.0,
            &index_layout,
            "indices",
        )?;
        let (value_bytes, _) = part(
            sparse.values.buffer_view.value(),
            sparse.values.byte_offset.0,
            &layout,
            "values",
        )?;
        let value_size = size;
        let isize = index_layout.element_size();
        for k in 0..n as usize {
            let target = index_layout.uint(&index_bytes[k * isize..], 0) as usize;
            let slot = out.get_mut(target).ok_or_else(|| {
                format!("{path}.sparse.indices[{k}] = {target} is out of range ({count} elements)")
            })?;
            *slot = convert(&layout, &value_bytes[k * value_size..(k + 1) * value_size]);
        }
    }
    Ok(out)
}

/// A primitive decoded from `KHR_draco_mesh_compression`.
pub struct DracoPrimitive {
    /// Triangle corners as point indices.
    pub indices: Vec<u32>,
    /// Attribute values by glTF semantic (`POSITION`, `JOINTS_0` …), as floats (integers
    /// converted, normalized per the glTF accessor), four per point, unused lanes zero.
    pub attributes: HashMap<String, Vec<[f32; 4]>>,
}

/// The vertex attributes of one primitive, from its accessors or its Draco data.
pub struct Attributes<'a> {
    pub root: &'a gltf::json::Root,
    pub data: &'a BufferData<'a>,
    pub accessors: HashMap<String, usize>,
    pub draco: Option<DracoPrimitive>,
    pub path: String,
}

impl Attributes<'_> {
    /// Attribute `semantic` with `N` components, if present.
    pub fn floats<const N: usize>(&self, semantic: &str) -> Result<Option<Vec<[f32; N]>>, String> {
        if let Some(values) = self.draco.as_ref().and_then(|d| d.attributes.get(semantic)) {
            return Ok(Some(
                values
                    .iter()
                    .map(|v| std::array::from_fn(|c| v[c]))
                    .collect(),
            ));
        }
        let Some(&index) = self.accessors.get(semantic) else {
            return Ok(None);
        };
        read_floats::<N>(self.root, self.data, index)
            .map(Some)
            .map_err(|e| format!("{}.attributes.{semantic}: {e}", self.path))
    }

    /// Attribute `semantic` as unsigned integers (`JOINTS_n`), if present.
    pub fn uints(&self, semantic: &str) -> Result<Option<Vec<[u32; 4]>>, String> {
        if let Some(values) = self.draco.as_ref().and_then(|d| d.attributes.get(semantic)) {
            return Ok(Some(values.iter().map(|v| v.map(|c| c as u32)).collect()));
        }
        let Some(&index) = self.accessors.get(semantic) else {
            return Ok(None);
        };
        read_uints::<4>(self.root, self.data, index)
            .map(Some)
            .map_err(|e| format!("{}.attributes.{semantic}: {e}", self.path))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root(json: &str) -> gltf::json::Root {
        serde_json::from_str(json).unwrap()
    }

    #[test]
    fn normalized_interleaved_and_sparse() {
        // Two i16 normalized VEC3 elements interleaved with a stride of 8, then a sparse
        // substitution of element 1 by u8 index / i16 values.
        let mut bytes = Vec::new();
        for v in [[32767i16, -32768, 0, 7], [16384, 0, -16384, 7]] {
            for c in v {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[1, 0, 0, 0]); // sparse index 1 (u8), padding
        for c in [0i16, 32767, 0] {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{}}}],
            "bufferViews":[{{"buffer":0,"byteLength":16,"byteStride":8}},
                           {{"buffer":0,"byteOffset":16,"byteLength":4}},
                           {{"buffer":0,"byteOffset":20,"byteLength":6}}],
            "accessors":[{{"bufferView":0,"componentType":5122,"normalized":true,"count":2,"type":"VEC3",
                "sparse":{{"count":1,"indices":{{"bufferView":1,"componentType":5121}},
                          "values":{{"bufferView":2}}}}}}]}}"#,
            bytes.len()
        );
        let root = root(&json);
        let data = BufferData {
            buffers: vec![&bytes],
            decoded_views: HashMap::new(),
        };
        let v = read_floats::<3>(&root, &data, 0).unwrap();
        assert_eq!(v[0], [1.0, -1.0, 0.0]);
        assert_eq!(v[1], [0.0, 1.0, 0.0]);
    }

    #[test]
    fn overruns_name_the_accessor() {
        let bytes = [0u8; 12];
        let json = r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":12}],
            "bufferViews":[{"buffer":0,"byteLength":12}],
            "accessors":[{"bufferView":0,"componentType":5126,"count":2,"type":"VEC3"},
                         {"bufferView":0,"componentType":5126,"count":1,"type":"VEC3",
                          "sparse":{"count":5,"indices":{"bufferView":0,"componentType":5125},
                                    "values":{"bufferView":0}}}]}"#;
        let root = root(json);
        let data = BufferData {
            buffers: vec![&bytes],
            decoded_views: HashMap::new(),
        };
        let e = read_floats::<3>(&root, &data, 0).unwrap_err();
        assert!(e.starts_with("accessors[0]: 2 elements"), "{e}");
        let e = read_floats::<3>(&root, &data, 1).unwrap_err();
        assert!(e.starts_with("accessors[1].sparse.count 5"), "{e}");
        let e = read_uints::<1>(&root, &data, 0).unwrap_err();
        assert!(e.contains("FLOAT"), "{e}");
    }
}
