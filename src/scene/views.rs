//! Saved views: cameras stored under a name in a small JSON file beside the scene
//! (`scene.glb` → `scene.glb.views.json`), written by the viewer's "save view" and read by
//! `--view NAME` in `view` and `render`. Only that file is ever written; its cameras keep full
//! f64 precision, so a restored view renders exactly like the one saved.

use super::Camera;
use anyhow::{Context, Result, bail};
use glam::DVec3;
use std::path::{Path, PathBuf};

/// One saved view.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SavedView {
    /// The name `--view` takes.
    pub name: String,
    /// Eye position (scene units).
    #[serde(with = "exact")]
    pub eye: [f64; 3],
    /// Unit view direction.
    #[serde(with = "exact")]
    pub forward: [f64; 3],
    /// Unit up vector.
    #[serde(with = "exact")]
    pub up: [f64; 3],
    /// Vertical field of view in radians (as the camera keeps it: degrees would not convert
    /// back to the same bits).
    #[serde(with = "exact")]
    pub yfov_radians: [f64; 1],
}

/// f64 values written as the shortest decimal strings that read back to the same bits (Rust's
/// `Display`) and read with `str::parse`, which is exact: serde_json's own number parser may be
/// a unit in the last place off (its `float_roundtrip` feature, which is exact, also makes an
/// f32 field of 1e39 in a glTF file an error instead of infinity), and a restored view must
/// render bit for bit.
mod exact {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer, const N: usize>(v: &[f64; N], s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter().map(|x| x.to_string()))
    }

    pub fn deserialize<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<[f64; N], D::Error> {
        let texts = Vec::<String>::deserialize(d)?;
        let values = texts
            .iter()
            .map(|t| {
                t.parse::<f64>()
                    .map_err(|e| D::Error::custom(format!("{t:?}: {e}")))
            })
            .collect::<Result<Vec<f64>, _>>()?;
        let n = values.len();
        values
            .try_into()
            .map_err(|_| D::Error::custom(format!("{n} numbers where {N} are needed")))
    }
}

#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
struct ViewsFile {
    views: Vec<SavedView>,
}

impl SavedView {
    /// `camera` saved as `name`.
    pub fn of(name: &str, camera: &Camera) -> Self {
        Self {
            name: name.to_string(),
            eye: camera.eye.to_array(),
            forward: camera.forward.to_array(),
            up: camera.up.to_array(),
            yfov_radians: [camera.yfov],
        }
    }

    /// The camera it restores.
    pub fn camera(&self) -> Camera {
        Camera {
            name: self.name.clone(),
            eye: DVec3::from(self.eye),
            forward: DVec3::from(self.forward),
            up: DVec3::from(self.up),
            yfov: self.yfov_radians[0],
        }
    }

    fn is_sane(&self) -> bool {
        let finite = |v: &[f64; 3]| v.iter().all(|x| x.is_finite());
        finite(&self.eye)
            && finite(&self.forward)
            && finite(&self.up)
            && DVec3::from(self.forward).length() > 0.5
            && self.yfov_radians[0] > 0.0
            && self.yfov_radians[0] < std::f64::consts::PI
    }
}

/// The views file of the scene at `scene`: its path with `.views.json` appended.
pub fn views_path(scene: &Path) -> PathBuf {
    let mut name = scene.as_os_str().to_owned();
    name.push(".views.json");
    PathBuf::from(name)
}

/// The views saved beside `scene` (none when there is no views file).
pub fn load_views(scene: &Path) -> Result<Vec<SavedView>> {
    let path = views_path(scene);
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(e).with_context(|| format!("{}: cannot read it", path.display())),
    };
    let file: ViewsFile = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a views file", path.display()))?;
    if let Some(bad) = file.views.iter().find(|v| !v.is_sane()) {
        bail!(
            "{}: view '{}' has a non-finite or zero vector or a field of view outside (0, 180)",
            path.display(),
            bad.name
        );
    }
    Ok(file.views)
}

/// The camera saved as `name` beside `scene`.
pub fn find_view(scene: &Path, name: &str) -> Result<Camera> {
    let views = load_views(scene)?;
    match views.iter().find(|v| v.name == name) {
        Some(v) => Ok(v.camera()),
        None if views.is_empty() => bail!(
            "--view {name}: no views are saved for {} ({} does not exist or is empty)",
            scene.display(),
            views_path(scene).display()
        ),
        None => bail!(
            "--view {name}: {} has no view of that name (it has: {})",
            views_path(scene).display(),
            views
                .iter()
                .map(|v| v.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        ),
    }
}

/// Saves `camera` as `name` beside `scene` (replacing a view of that name), writing only the
/// views file (through a temporary file renamed over it). Returns the file's path.
pub fn save_view(scene: &Path, name: &str, camera: &Camera) -> Result<PathBuf> {
    let mut views = load_views(scene)?;
    let view = SavedView::of(name, camera);
    match views.iter_mut().find(|v| v.name == name) {
        Some(v) => *v = view,
        None => views.push(view),
    }
    let path = views_path(scene);
    let text = serde_json::to_string_pretty(&ViewsFile { views })?;
    let tmp = path.with_extension("json.tmp");
    std::fs::write(&tmp, text + "\n")
        .with_context(|| format!("{}: cannot write it", tmp.display()))?;
    std::fs::rename(&tmp, &path).with_context(|| format!("{}: cannot write it", path.display()))?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_saved_view_comes_back_exactly_and_only_its_file_is_written() {
        let dir = std::env::temp_dir().join(format!("penumbra-views-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("room.glb");
        std::fs::write(&scene, b"not touched").unwrap();
        let cam = Camera::look_at(
            "x",
            DVec3::new(0.1, 1.7, -3.3),
            DVec3::new(1.0 / 3.0, 0.2, 0.0),
            0.7,
        );
        let path = save_view(&scene, "desk", &cam).unwrap();
        assert_eq!(path, dir.join("room.glb.views.json"));
        save_view(
            &scene,
            "door",
            &Camera {
                yfov: 1.1,
                ..cam.clone()
            },
        )
        .unwrap();
        let back = find_view(&scene, "desk").unwrap();
        assert_eq!(
            (back.eye, back.forward, back.up),
            (cam.eye, cam.forward, cam.up)
        );
        assert!((back.yfov - cam.yfov).abs() < 1e-15);
        // Saving a name again replaces it.
        save_view(&scene, "desk", &Camera { yfov: 0.5, ..cam }).unwrap();
        assert_eq!(load_views(&scene).unwrap().len(), 2);
        assert_eq!(std::fs::read(&scene).unwrap(), b"not touched");
        let names: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 2, "{names:?}");
        let e = find_view(&scene, "window").unwrap_err().to_string();
        assert!(e.contains("desk, door"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
