//! The scene path checked before the glTF parser sees it (and before the viewer looks for a
//! display): it exists, is a readable regular file, is not empty, and starts like glTF (JSON or
//! a GLB header whose length the file holds). Anything else is one line naming the real
//! problem, another format by its signature ("it looks like a Wavefront OBJ") or a GLB cut
//! short, rather than the parser's first complaint.

use crate::bench::thousands;
use anyhow::{Result, bail};
use std::io::Read;
use std::path::Path;

/// Bytes read from the start of the file to recognise its format.
const HEAD_BYTES: usize = 4096;

/// The GLB header: magic `glTF`, version, total length (little-endian u32s).
const GLB_HEADER_BYTES: usize = 12;

/// Checks that `path` can be a glTF scene: one line naming the file and what is wrong if not.
pub fn check(path: &Path) -> Result<()> {
    let name = path.display();
    let meta = match std::fs::metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => bail!("{name} does not exist"),
        Err(e) => bail!("{name}: cannot read the file: {}", io_reason(&e)),
    };
    if meta.is_dir() {
        bail!("{name} is a folder, not a glTF file");
    }
    if !meta.is_file() {
        bail!("{name}: cannot read the file: not a regular file");
    }
    let mut head = Vec::with_capacity(HEAD_BYTES);
    std::fs::File::open(path)
        .and_then(|f| f.take(HEAD_BYTES as u64).read_to_end(&mut head))
        .map_err(|e| anyhow::anyhow!("{name}: cannot read the file: {}", io_reason(&e)))?;
    if meta.len() == 0 {
        bail!("{name} is empty");
    }
    if head.starts_with(b"glTF") {
        return check_glb_length(&name.to_string(), &head, meta.len());
    }
    if starts_like_json(&head) {
        return Ok(());
    }
    match looks_like(&head, meta.len()) {
        Some(format) => bail!("{name} is not a glTF file (it looks like {format})"),
        None => bail!(
            "{name} is not a glTF file (it starts with neither '{{' (a .gltf) nor 'glTF' (a .glb))"
        ),
    }
}

/// The OS error's reason without Rust's "(os error N)" suffix.
fn io_reason(e: &std::io::Error) -> String {
    match e.kind() {
        std::io::ErrorKind::PermissionDenied => "permission denied".into(),
        _ => e.to_string(),
    }
}

/// A GLB is at least its header long, and as long as the header says.
fn check_glb_length(name: &str, head: &[u8], file_len: u64) -> Result<()> {
    if head.len() < GLB_HEADER_BYTES {
        bail!(
            "{name} is truncated: a GLB header is {GLB_HEADER_BYTES} bytes, the file has {}",
            thousands(file_len)
        );
    }
    let declared = u32::from_le_bytes([head[8], head[9], head[10], head[11]]) as u64;
    if declared > file_len {
        bail!(
            "{name} is truncated: the GLB header says {} bytes, the file has {}",
            thousands(declared),
            thousands(file_len)
        );
    }
    Ok(())
}

/// Whether the bytes start, after an optional UTF-8 byte order mark and white space, with `{`.
fn starts_like_json(head: &[u8]) -> bool {
    let text = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(head);
    text.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{')
}

/// The format a file's first bytes (and its length) give away, for the error message.
fn looks_like(head: &[u8], file_len: u64) -> Option<&'static str> {
    const SIGNATURES: &[(&[u8], &str)] = &[
        (b"Kaydara FBX Binary", "an Autodesk FBX file"),
        (b"; FBX", "an Autodesk FBX file (text)"),
        (b"PXR-USDC", "a USD file (binary .usdc)"),
        (b"#usda", "a USD file (text .usda)"),
        (
            b"PK\x03\x04",
            "a zip archive (unpack it and open the .gltf or .glb inside)",
        ),
        (b"\x89PNG", "a PNG image"),
        (b"\xFF\xD8\xFF", "a JPEG image"),
        (b"\xABKTX 20", "a KTX2 texture"),
        (b"#?RADIANCE", "a Radiance .hdr image"),
        (b"#?RGBE", "a Radiance .hdr image"),
        (b"\x76\x2F\x31\x01", "an OpenEXR image"),
        (b"\x1F\x8B", "a gzip archive"),
        (b"7z\xBC\xAF\x27\x1C", "a 7-Zip archive"),
        (
            b"BLENDER",
            "a Blender file (export it as glTF from Blender)",
        ),
        (
            b"version https://git-lfs",
            "a Git LFS pointer (run `git lfs pull` to fetch the file)",
        ),
    ];
    if let Some((_, format)) = SIGNATURES.iter().find(|(sig, _)| head.starts_with(sig)) {
        return Some(*format);
    }
    if head.starts_with(b"RIFF") && head.get(8..12) == Some(&b"WEBP"[..]) {
        return Some("a WebP image");
    }
    if binary_stl_length(head) == Some(file_len) {
        return Some("a binary STL file");
    }
    let text = String::from_utf8_lossy(head);
    let text = text.trim_start_matches('\u{FEFF}').trim_start();
    let lower = text.to_ascii_lowercase();
    if lower.starts_with("ply\n") || lower.starts_with("ply\r\n") {
        return Some("a PLY file");
    }
    if lower.starts_with("solid") && lower.contains("facet") {
        return Some("an STL file (text)");
    }
    if lower.starts_with("<!doctype html") || lower.starts_with("<html") {
        return Some("a web page (a download that saved the page instead of the file?)");
    }
    if lower.starts_with("<?xml") || lower.starts_with('<') {
        return Some(if lower.contains("<collada") {
            "a COLLADA (.dae) file"
        } else {
            "an XML file"
        });
    }
    if looks_like_obj(text) {
        return Some("a Wavefront OBJ");
    }
    None
}

/// The file length a binary STL of this header implies: 80 bytes of header, a triangle
/// count, 50 bytes a triangle.
fn binary_stl_length(head: &[u8]) -> Option<u64> {
    let count = head.get(80..84)?;
    let count = u32::from_le_bytes([count[0], count[1], count[2], count[3]]) as u64;
    (count > 0).then_some(84 + 50 * count)
}

/// Whether the text's statements (its lines, less comments and blanks) are OBJ statements,
/// a vertex or face among them.
fn looks_like_obj(text: &str) -> bool {
    const STATEMENTS: &[&str] = &[
        "v", "vn", "vt", "vp", "f", "l", "p", "o", "g", "s", "mtllib", "usemtl",
    ];
    let statements: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| l.split_whitespace().next().unwrap_or(""))
        .take(16)
        .collect();
    statements.iter().all(|s| STATEMENTS.contains(s))
        && statements.iter().any(|s| matches!(*s, "v" | "f"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn other_formats_are_named_by_their_first_bytes() {
        let mut stl = vec![0u8; 84 + 50];
        stl[80] = 1;
        let obj = "# Blender\nmtllib a.mtl\no Cube\nv 1 1 1\nv 0 0 0\nf 1 2 3\n";
        for (head, expect) in [
            (obj.as_bytes(), "Wavefront OBJ"),
            (&b"ply\nformat ascii 1.0\n"[..], "PLY"),
            (&b"Kaydara FBX Binary  \0\x1a\0"[..], "FBX"),
            (&b"solid cube\n facet normal 0 0 1\n"[..], "STL"),
            (stl.as_slice(), "binary STL"),
            (&b"PXR-USDC"[..], "USD"),
            (&b"#usda 1.0\n"[..], "USD"),
            (&b"PK\x03\x04\x14\0"[..], "zip"),
            (&b"\x89PNG\r\n\x1a\n"[..], "PNG"),
            (&b"\xFF\xD8\xFF\xE0"[..], "JPEG"),
            (&b"<?xml version=\"1.0\"?><COLLADA>"[..], "COLLADA"),
            (
                &b"version https://git-lfs.github.com/spec/v1\n"[..],
                "git lfs pull",
            ),
        ] {
            let found = looks_like(head, head.len() as u64);
            assert!(
                found.is_some_and(|f| f.contains(expect)),
                "{expect}: {found:?}"
            );
        }
        // Text that merely mentions an OBJ keyword, or random bytes, is not given a name.
        assert_eq!(looks_like(b"hello world\nv 1 2 3\n", 20), None);
        assert_eq!(looks_like(&[7u8; 100], 100), None);
    }

    #[test]
    fn json_may_follow_a_byte_order_mark_and_white_space() {
        assert!(starts_like_json(b"\xEF\xBB\xBF \n{\"asset\":{}}"));
        assert!(!starts_like_json(b"v 1 2 3"));
        assert!(!starts_like_json(b""));
    }

    #[test]
    fn a_glb_shorter_than_its_header_says_is_truncated() {
        let mut head = b"glTF".to_vec();
        head.extend(2u32.to_le_bytes());
        head.extend(1_234_567u32.to_le_bytes());
        let e = check_glb_length("a.glb", &head, 512)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "a.glb is truncated: the GLB header says 1,234,567 bytes, the file has 512"
        );
        assert!(check_glb_length("a.glb", &head, 1_234_567).is_ok());
        let e = check_glb_length("a.glb", b"glTF\x02", 5)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("a GLB header is 12 bytes, the file has 5"),
            "{e}"
        );
    }
}
