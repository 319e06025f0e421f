//! Parsing and validating a glTF document before anything reads it.
//!
//! The JSON (or the GLB container's JSON chunk) is parsed into gltf-json's `Root` and checked
//! with gltf-json's validation (dangling indices, invalid enum values, missing required
//! properties), plus the checks gltf-json leaves out that the `gltf` crate would otherwise
//! panic on or allocate from: the camera type's object, an image's source, accessor counts.
//! Each problem is `JSON path: what is wrong`; the first one is the load error.

use super::limits;
use super::sources::Bytes;
use gltf::json::{self, validation::Error as JsonError, validation::Validate};

/// glTF extensions penumbra reads, or may safely ignore when rendering. A file that requires
/// any other extension is refused; one that only uses another gets a warning. The one list
/// of supported extensions: the import and the docs' extension table follow it.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_anisotropy",
    "KHR_materials_clearcoat",
    "KHR_materials_diffuse_transmission",
    "KHR_materials_dispersion",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_iridescence",
    "KHR_materials_sheen",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_unlit",
    "KHR_materials_variants",
    "KHR_materials_volume",
    "KHR_texture_transform",
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "KHR_draco_mesh_compression",
    "EXT_texture_webp",
    "KHR_texture_basisu",
];

/// Texture extensions that name an image by their `source` (instead of the core `source`), in
/// the order the importer prefers them.
pub const IMAGE_SOURCE_EXTENSIONS: &[&str] = &["KHR_texture_basisu", "EXT_texture_webp"];

/// A parsed document that passed validation, with the GLB binary chunk if there was one.
pub struct Parsed {
    /// The document; every index in it is in range and every enum valid.
    pub document: gltf::Document,
    /// The GLB `BIN` chunk.
    pub blob: Option<Bytes>,
    /// Node transforms as written, in f64 (gltf-json reads them as f32).
    pub precise_nodes: Vec<PreciseNode>,
}

/// A node's transform read from the JSON text in f64, so that a scene placed at survey
/// coordinates keeps the relative placement of its nodes (f32 keeps only about half a unit at
/// 10⁷). Empty when the text cannot be read this way; the f32 values are used then.
#[derive(serde::Deserialize, Default, Clone, Debug)]
pub struct PreciseNode {
    /// `translation`.
    pub translation: Option<[f64; 3]>,
    /// `rotation` (x, y, z, w).
    pub rotation: Option<[f64; 4]>,
    /// `scale`.
    pub scale: Option<[f64; 3]>,
    /// `matrix`, column-major.
    pub matrix: Option<[f64; 16]>,
}

/// The nodes' transforms in f64, or none when any of them does not read as numbers.
fn precise_nodes(json: &[u8]) -> Vec<PreciseNode> {
    #[derive(serde::Deserialize)]
    struct Nodes {
        #[serde(default)]
        nodes: Vec<PreciseNode>,
    }
    serde_json::from_slice::<Nodes>(json)
        .map(|n| n.nodes)
        .unwrap_or_default()
}

/// Parses `.gltf` JSON or `.glb` bytes and validates the document. Warnings (unsupported
/// optional extensions) are appended to `warnings`. A GLB file's `BIN` chunk keeps the
/// allocation of `bytes` (moved down to its start, not copied): a file of meshes is held once.
pub fn parse(bytes: Bytes, warnings: &mut Vec<String>) -> Result<Parsed, String> {
    // A GLB header's length word (bytes 8..12) against the file's length.
    let glb_lengths = bytes.starts_with(b"glTF").then(|| {
        let header = bytes
            .get(8..12)
            .map_or(0, |w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]));
        (header as u64, bytes.len() as u64)
    });
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
        let glb =
            gltf::Glb::from_slice(&bytes).map_err(|e| format!("not a valid GLB file: {e}"))?;
        let json = Bytes::Owned(glb.json.into_owned());
        // Where the BIN chunk lies in `bytes` (`from_slice` borrows it from there).
        let bin = glb.bin.map(|b| {
            let start = b.as_ptr() as usize - bytes.as_ptr() as usize;
            start..start + b.len()
        });
        (json, bin.map(|range| bytes.into_range(range)))
    } else {
        (bytes, None)
    };
    let root =
        json::Root::from_slice(&json_bytes).map_err(|e| format!("not a valid glTF file: {e}"))?;
    check_extensions(&root, warnings)?;
    let problems = problems(&root);
    if let Some(first) = problems.first() {
        let more = match problems.len() {
            1 => String::new(),
            n => format!(" (and {} more problems)", n - 1),
        };
        return Err(format!("{first}{more}"));
    }
    super::lenient::warn_invalid(&root, glb_lengths, warnings);
    let precise_nodes = precise_nodes(&json_bytes);
    Ok(Parsed {
        document: gltf::Document::from_json_without_validation(root),
        blob,
        precise_nodes,
    })
}

/// Rejects unsupported required extensions and warns about unsupported optional ones.
fn check_extensions(root: &json::Root, warnings: &mut Vec<String>) -> Result<(), String> {
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(format!(
                "extensionsRequired[{i}]: requires the unsupported extension {ext}"
            ));
        }
    }
    for ext in &root.extensions_used {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            warnings.push(format!(
                "optional extension {ext} is not supported and is ignored"
            ));
        }
    }
    Ok(())
}

/// Every problem of the document, as `path: what`, in document order.
pub fn problems(root: &json::Root) -> Vec<String> {
    // gltf-json's primitive check indexes the accessors with POSITION's index unchecked, so
    // dangling POSITION indices are reported first and stop the validation.
    let mut out = Vec::new();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let name = match semantic {
                        json::validation::Checked::Valid(s) => s.to_string(),
                        json::validation::Checked::Invalid => "?".into(),
                    };
                    out.push(format!(
                        "meshes[{m}].primitives[{p}].attributes[\"{name}\"]: {}",
                        describe(JsonError::IndexOutOfBounds)
                    ));
                }
            }
        }
    }
    if !out.is_empty() {
        return out;
    }
    root.validate(root, json::Path::new, &mut |path, error| {
        let path = extension_names(path().as_str());
        if tolerated(&path, error) {
            return;
        }
        out.push(format!("{path}: {}", describe(error)));
    });
    out.extend(beyond_gltf_json(root));
    out
}

/// gltf-json reports that penumbra accepts: required extensions (checked against
/// [`SUPPORTED_EXTENSIONS`] instead of gltf-json's own list), POSITION without min/max
/// (exporters often leave them out and nothing here reads them), and an accessor without a
/// buffer view (Draco-compressed primitives have none; reading such an accessor fails there),
/// a texture whose only source is an extension's, and anything in `animations`.
fn tolerated(path: &str, error: JsonError) -> bool {
    // A bad animation channel is skipped with a warning when the clips are read
    // (`animation::read_clips`), not the whole file refused.
    if path.starts_with("animations[") {
        return true;
    }
    match error {
        JsonError::Unsupported => path.starts_with("extensionsRequired"),
        JsonError::Missing => {
            path.ends_with("attributes[\"POSITION\"].min")
                || path.ends_with("attributes[\"POSITION\"].max")
                || (path.starts_with("accessors[") && path.ends_with("].bufferView"))
                // EXT_texture_webp (or KHR_texture_basisu) names the texture's image in its
                // extension; the importer falls back to it, or leaves the texture out.
                || (path.starts_with("textures[") && path.ends_with("].source"))
        }
        _ => false,
    }
}

/// gltf-json names extension objects in paths by their Rust field names
/// (`khrLightsPunctual`); this puts back the names the file uses (`KHR_lights_punctual`).
fn extension_names(path: &str) -> String {
    let mut out = path.to_string();
    for ext in SUPPORTED_EXTENSIONS {
        let mut parts = ext.split('_');
        let mut camel = parts.next().unwrap_or_default().to_ascii_lowercase();
        for p in parts {
            let mut c = p.chars();
            if let Some(first) = c.next() {
                camel.push(first.to_ascii_uppercase());
                camel.push_str(c.as_str());
            }
        }
        out = out.replace(&format!(".{camel}"), &format!(".{ext}"));
    }
    out
}

fn describe(error: JsonError) -> &'static str {
    match error {
        JsonError::IndexOutOfBounds => "index out of range",
        JsonError::Invalid => "invalid value",
        JsonError::Missing => "missing",
        JsonError::Oversize => "size too large for this machine",
        JsonError::Unsupported => "unsupported extension",
    }
}

/// Whether accessor `a` has a type and component type the specification allows for
/// `semantic` (with `KHR_mesh_quantization`, the wider set it allows); `None` when it does.
fn attribute_type_problem(
    semantic: &json::mesh::Semantic,
    a: &json::Accessor,
    quantized: bool,
) -> Option<&'static str> {
    use json::accessor::ComponentType as C;
    use json::accessor::Type as T;
    use json::mesh::Semantic as S;
    use json::validation::Checked::Valid;
    let (Valid(ty), Valid(json::accessor::GenericComponentType(c))) = (a.type_, a.component_type)
    else {
        return None;
    };
    let small_int = matches!(c, C::I8 | C::U8 | C::I16 | C::U16);
    let (types_ok, components_ok) = match semantic {
        S::Positions => (ty == T::Vec3, c == C::F32 || (quantized && small_int)),
        S::Normals => (
            ty == T::Vec3,
            c == C::F32 || (quantized && matches!(c, C::I8 | C::I16)),
        ),
        S::Tangents => (
            ty == T::Vec4,
            c == C::F32 || (quantized && matches!(c, C::I8 | C::I16)),
        ),
        S::TexCoords(_) => (
            ty == T::Vec2,
            matches!(c, C::F32 | C::U8 | C::U16) || (quantized && small_int),
        ),
        S::Colors(_) => (
            matches!(ty, T::Vec3 | T::Vec4),
            matches!(c, C::F32 | C::U8 | C::U16),
        ),
        S::Joints(_) => (ty == T::Vec4, matches!(c, C::U8 | C::U16)),
        S::Weights(_) => (ty == T::Vec4, matches!(c, C::F32 | C::U8 | C::U16)),
        #[allow(unreachable_patterns)]
        _ => (true, true),
    };
    match (types_ok, components_ok) {
        (true, true) => None,
        (false, _) => Some("has the wrong type for this attribute"),
        (true, false) => Some("has the wrong componentType for this attribute"),
    }
}

/// Checks gltf-json leaves out: the `gltf` crate unwraps these, or allocates what they claim.
fn beyond_gltf_json(root: &json::Root) -> Vec<String> {
    use json::validation::Checked::Valid;
    let mut out = Vec::new();
    for (i, c) in root.cameras.iter().enumerate() {
        let ok = match c.type_ {
            Valid(json::camera::Type::Perspective) => c.perspective.is_some(),
            Valid(json::camera::Type::Orthographic) => c.orthographic.is_some(),
            _ => true,
        };
        if !ok {
            out.push(format!(
                "cameras[{i}]: the object its type names is missing"
            ));
        }
    }
    for (i, image) in root.images.iter().enumerate() {
        match (&image.buffer_view, &image.uri) {
            (Some(_), _) if image.mime_type.is_none() => {
                out.push(format!(
                    "images[{i}].mimeType: missing (required with bufferView)"
                ));
            }
            (None, None) => out.push(format!("images[{i}]: neither uri nor bufferView")),
            _ => {}
        }
    }
    // The image sources the texture extensions name (read as raw JSON by the importer).
    for (i, t) in root.textures.iter().enumerate() {
        for ext in IMAGE_SOURCE_EXTENSIONS {
            let Some(object) = t.extensions.as_ref().and_then(|e| e.others.get(*ext)) else {
                continue;
            };
            let at = format!("textures[{i}].extensions.{ext}");
            match object.get("source") {
                None if object.is_object() => out.push(format!("{at}.source: missing")),
                None => out.push(format!("{at}: invalid value")),
                Some(s) => match s.as_u64() {
                    Some(n) if n < root.images.len() as u64 => {}
                    Some(_) => out.push(format!("{at}.source: index out of range")),
                    None => out.push(format!("{at}.source: invalid value")),
                },
            }
        }
    }
    let quantized = root
        .extensions_used
        .iter()
        .any(|e| e == "KHR_mesh_quantization");
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let at = format!("meshes[{m}].primitives[{p}]");
            for (semantic, index) in &prim.attributes {
                if let (Valid(semantic), Some(a)) = (semantic, root.accessors.get(index.value()))
                    && let Some(why) = attribute_type_problem(semantic, a, quantized)
                {
                    out.push(format!(
                        "{at}.attributes[\"{}\"]: accessors[{}] {why}",
                        semantic.to_string(),
                        index.value()
                    ));
                }
            }
            if let Some(a) = prim
                .indices
                .as_ref()
                .and_then(|i| root.accessors.get(i.value()).map(|a| (i.value(), a)))
            {
                use json::accessor::ComponentType as C;
                let ok = matches!(a.1.type_, Valid(json::accessor::Type::Scalar))
                    && matches!(
                        a.1.component_type,
                        Valid(json::accessor::GenericComponentType(
                            C::U8 | C::U16 | C::U32
                        ))
                    );
                if !ok {
                    out.push(format!(
                        "{at}.indices: accessors[{}] is not SCALAR of unsigned byte, short or int",
                        a.0
                    ));
                }
            }
        }
    }
    for (i, a) in root.accessors.iter().enumerate() {
        let count = a.count.0;
        if count == 0 {
            out.push(format!("accessors[{i}].count: must be at least 1"));
        }
        if a.buffer_view.is_none() && count > limits::MAX_UNBACKED_ACCESSOR_COUNT {
            out.push(format!(
                "accessors[{i}].count: {count} elements without a bufferView is more than the \
                 limit of {}",
                limits::MAX_UNBACKED_ACCESSOR_COUNT
            ));
        }
        if let Some(sparse) = &a.sparse {
            let n = sparse.count.0;
            if n == 0 || n > count {
                out.push(format!(
                    "accessors[{i}].sparse.count: {n} is not within 1..={count} (the accessor's count)"
                ));
            }
        }
    }
    out
}
