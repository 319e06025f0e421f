//! Animation: the file's clips evaluated at any time into node transforms, skins, morph
//! weights, cameras and lights, and a scene brought to that pose in place.
//!
//! A node's local transform is its rest TRS with the animated properties replaced by the
//! clip's values; world transforms nest them down each node's parent chain (glTF nodes have
//! one parent). A skinned mesh is placed by its joints alone (`world(joint) × inverse bind`;
//! its node's transform is ignored, glTF 2.0 § 3.7.3), a morphed one by its node. Nodes no
//! clip reaches keep the matrices the importer placed them with, bit for bit.

mod clip;
mod rig;

pub use clip::{Channel, Clip, Interp, Target, read_clips, slerp};
pub use rig::{Rig, RigData};

use super::accessor::{self, BufferData};
use super::validate::PreciseNode;
use super::{Camera, Scene};
use glam::{DMat4, DQuat, DVec3};
use std::sync::Arc;
use std::time::Instant;

/// A node's rest transform: its matrix, and its TRS when it has no matrix (what channels
/// replace).
#[derive(Clone, Debug)]
struct RestNode {
    matrix: DMat4,
    trs: Option<(DVec3, DQuat, DVec3)>,
}

/// A skin: its joints (node indices) and inverse bind matrices (identity where absent).
#[derive(Clone, Debug)]
pub struct Skin {
    /// The joint nodes, in the skin's order.
    pub joints: Vec<usize>,
    /// `bind_from_world` of each joint.
    pub inverse_binds: Vec<DMat4>,
}

/// An object of the scene that a pose moves or deforms.
#[derive(Clone, Debug)]
pub struct Driven {
    /// Index in `Scene::objects`.
    pub object: usize,
    /// The node placing it.
    pub node: usize,
    /// What deforms its mesh (skin or morph targets), when something does.
    pub rig: Option<Arc<Rig>>,
}

/// Everything needed to pose a loaded scene at any time of any clip.
#[derive(Clone, Debug, Default)]
pub struct Animation {
    /// The file's clips, in order.
    pub clips: Vec<Clip>,
    rest: Vec<RestNode>,
    parent: Vec<Option<usize>>,
    /// Node indices with every parent before its children.
    order: Vec<usize>,
    /// The file's skins (only those some placed mesh uses are read; the others are empty).
    pub skins: Vec<Skin>,
    /// The objects placed by nodes (every mesh node the importer kept).
    pub objects: Vec<Driven>,
    /// Scene cameras placed by nodes: (index in `Scene::cameras`, node).
    pub cameras: Vec<(usize, usize)>,
    /// Scene lights placed by nodes: (index in `Scene::lights`, node).
    pub lights: Vec<(usize, usize)>,
}

/// Node transforms and morph weights at one instant.
#[derive(Clone, Debug)]
pub struct NodePose {
    /// World from node, for every node.
    pub worlds: Vec<DMat4>,
    /// Animated morph weights by node (`None`: the node's defaults).
    pub weights: Vec<Option<Vec<f32>>>,
}

/// What [`Animation::apply`] changed and what it took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Applied {
    /// Objects whose transform changed.
    pub moved: usize,
    /// Objects whose mesh was deformed (skins, morph targets).
    pub deformed: usize,
    /// Cameras and lights placed anew.
    pub cameras_and_lights: usize,
    /// Evaluating the clip into node transforms and joint matrices, ms.
    pub evaluate_ms: f64,
    /// Deforming meshes (morph targets and skins), ms.
    pub deform_ms: f64,
}

impl Animation {
    /// The node data a pose needs: each node's rest transform (from `precise` where the file
    /// could be read in f64, as the importer places nodes) and the parent chains.
    pub fn new(document: &gltf::Document, precise: &[PreciseNode], clips: Vec<Clip>) -> Self {
        let rest: Vec<RestNode> = document
            .nodes()
            .map(|n| {
                let p = precise.get(n.index());
                let matrix = super::pose::node_matrix(&n, p).unwrap_or(DMat4::IDENTITY);
                let trs = match n.transform() {
                    gltf::scene::Transform::Matrix { .. } => None,
                    gltf::scene::Transform::Decomposed {
                        translation,
                        rotation,
                        scale,
                    } => {
                        let p = p.cloned().unwrap_or_default();
                        Some((
                            DVec3::from(p.translation.unwrap_or(translation.map(f64::from))),
                            DQuat::from_array(p.rotation.unwrap_or(rotation.map(f64::from)))
                                .normalize(),
                            DVec3::from(p.scale.unwrap_or(scale.map(f64::from))),
                        ))
                    }
                };
                RestNode { matrix, trs }
            })
            .collect();
        let parent = super::pose::parents(document);
        // Roots first, then each node after its parent (the importer has checked that the
        // parent chains end).
        let mut children = vec![Vec::new(); parent.len()];
        let mut order: Vec<usize> = Vec::with_capacity(parent.len());
        for (n, p) in parent.iter().enumerate() {
            match p {
                Some(p) => children[*p].push(n),
                None => order.push(n),
            }
        }
        let mut at = 0;
        while at < order.len() {
            let n = order[at];
            order.extend_from_slice(&children[n]);
            at += 1;
        }
        Self {
            clips,
            rest,
            parent,
            order,
            ..Self::default()
        }
    }

    /// Reads skin `index` (once; later calls return at once), or why it cannot be used.
    pub fn read_skin(
        &mut self,
        root: &gltf::json::Root,
        data: &BufferData,
        index: usize,
    ) -> Result<(), String> {
        if self.skins.len() <= index {
            self.skins.resize(
                root.skins.len().max(index + 1),
                Skin {
                    joints: Vec::new(),
                    inverse_binds: Vec::new(),
                },
            );
        }
        if !self.skins[index].joints.is_empty() {
            return Ok(());
        }
        let path = format!("skins[{index}]");
        let json = &root.skins[index];
        let binds = match json.inverse_bind_matrices {
            Some(a) => accessor::read_floats::<16>(root, data, a.value())
                .map_err(|e| format!("{path}.inverseBindMatrices: {e}"))?,
            None => Vec::new(),
        };
        if !binds.is_empty() && binds.len() < json.joints.len() {
            return Err(format!(
                "{path}: {} inverse bind matrices for {} joints",
                binds.len(),
                json.joints.len()
            ));
        }
        let mut joints = Vec::with_capacity(json.joints.len());
        for (k, joint) in json.joints.iter().enumerate() {
            if joint.value() >= self.rest.len() {
                return Err(format!(
                    "{path}.joints[{k}]: nodes[{}] does not exist",
                    joint.value()
                ));
            }
            joints.push(joint.value());
        }
        let inverse_binds = (0..joints.len())
            .map(|k| {
                binds.get(k).map_or(DMat4::IDENTITY, |m| {
                    DMat4::from_cols_array(&m.map(f64::from))
                })
            })
            .collect();
        self.skins[index] = Skin {
            joints,
            inverse_binds,
        };
        Ok(())
    }

    /// The clip named `name`, or numbered so; the error lists the clips there are.
    pub fn find_clip(&self, name: &str) -> Result<usize, String> {
        if let Some(i) = self.clips.iter().position(|c| c.name == name) {
            return Ok(i);
        }
        if let Ok(i) = name.trim().parse::<usize>()
            && i < self.clips.len()
        {
            return Ok(i);
        }
        let names: Vec<String> = self
            .clips
            .iter()
            .enumerate()
            .map(|(i, c)| format!("{i} '{}'", c.name))
            .collect();
        Err(if names.is_empty() {
            format!("no clip '{name}': the scene has no animations")
        } else {
            format!("no clip '{name}'; the clips are {}", names.join(", "))
        })
    }

    /// `t` seconds into clip `clip` as a time on its timeline: wrapped over its duration when
    /// `looping`, else held at its ends.
    pub fn clip_time(&self, clip: usize, t: f64, looping: bool) -> f64 {
        let d = self.clips.get(clip).map_or(0.0, |c| c.duration);
        if d <= 0.0 || !t.is_finite() {
            return 0.0;
        }
        if looping {
            t.rem_euclid(d)
        } else {
            t.clamp(0.0, d)
        }
    }

    /// Every node's world transform and animated weights at time `t` of `clip` (`None`: the
    /// rest pose).
    pub fn evaluate(&self, clip: Option<usize>, t: f64) -> NodePose {
        let count = self.rest.len();
        let mut trs: Vec<Option<(DVec3, DQuat, DVec3)>> = vec![None; count];
        let mut weights: Vec<Option<Vec<f32>>> = vec![None; count];
        let mut value = [0.0f64; 4];
        for channel in clip
            .and_then(|c| self.clips.get(c))
            .map_or(&[][..], |c| &c.channels)
        {
            let n = channel.node;
            if channel.target == Target::Weights {
                let mut w = vec![0.0f64; channel.width];
                channel.sample(t, &mut w);
                weights[n] = Some(w.into_iter().map(|w| w as f32).collect());
                continue;
            }
            let Some(rest) = self.rest[n].trs else {
                continue;
            };
            channel.sample(t, &mut value);
            let slot = trs[n].get_or_insert(rest);
            match channel.target {
                Target::Translation => slot.0 = DVec3::from_slice(&value),
                Target::Rotation => slot.1 = DQuat::from_slice(&value),
                _ => slot.2 = DVec3::from_slice(&value),
            }
        }
        let mut worlds = vec![DMat4::IDENTITY; count];
        for &n in &self.order {
            let local = match trs[n] {
                Some((t, r, s)) => DMat4::from_scale_rotation_translation(s, r, t),
                None => self.rest[n].matrix,
            };
            worlds[n] = match self.parent[n] {
                Some(p) => worlds[p] * local,
                None => local,
            };
        }
        NodePose { worlds, weights }
    }

    /// The joint matrices of skin `skin` (world from bind space) under `pose`.
    pub fn joint_matrices(&self, skin: usize, pose: &NodePose) -> Vec<DMat4> {
        let s = &self.skins[skin];
        s.joints
            .iter()
            .zip(&s.inverse_binds)
            .map(|(&j, ib)| pose.worlds[j] * *ib)
            .collect()
    }

    /// Brings `scene` (the scene this animation was loaded with) to time `t` of `clip` (`None`:
    /// the rest pose): objects moved, meshes deformed, cameras and lights placed. An object
    /// whose node the pose makes singular (scaled to zero) is hidden until a pose shows it.
    pub fn apply(&self, scene: &mut Scene, clip: Option<usize>, t: f64) -> Applied {
        let started = Instant::now();
        let pose = self.evaluate(clip, t);
        let joints: Vec<Option<Vec<DMat4>>> = (0..self.skins.len())
            .map(|s| (!self.skins[s].joints.is_empty()).then(|| self.joint_matrices(s, &pose)))
            .collect();
        let mut applied = Applied {
            evaluate_ms: started.elapsed().as_secs_f64() * 1e3,
            ..Applied::default()
        };
        let deforming = Instant::now();
        for d in &self.objects {
            let Some(object) = scene.objects.get_mut(d.object) else {
                continue;
            };
            let skin = d.rig.as_ref().and_then(|r| r.skin);
            let world = if skin.is_some() {
                DMat4::IDENTITY
            } else {
                pose.worlds[d.node]
            };
            let usable = world.is_finite()
                && world.determinant() != 0.0
                && world.inverse().as_mat4().is_finite();
            if usable && world != object.world_from_object {
                object.world_from_object = world;
                applied.moved += 1;
            }
            object.visible = usable;
            if let Some(rig) = &d.rig {
                let weights = pose.weights[d.node]
                    .as_deref()
                    .unwrap_or(&rig.default_weights);
                let joints = skin
                    .and_then(|s| joints.get(s))
                    .and_then(Option::as_deref)
                    .unwrap_or_default();
                rig.pose_into(weights, joints, Arc::make_mut(&mut object.mesh));
                applied.deformed += 1;
            }
        }
        applied.deform_ms = deforming.elapsed().as_secs_f64() * 1e3;
        for &(c, node) in &self.cameras {
            if let Some(camera) = scene.cameras.get_mut(c) {
                place_camera(camera, &pose.worlds[node]);
                applied.cameras_and_lights += 1;
            }
        }
        for &(l, node) in &self.lights {
            if let Some(light) = scene.lights.get_mut(l) {
                let world = pose.worlds[node];
                light.position = world.transform_point3(DVec3::ZERO);
                light.direction =
                    (-world.transform_vector3(DVec3::Z)).normalize_or(light.direction);
                applied.cameras_and_lights += 1;
            }
        }
        // Meshes deformed in place keep their addresses: the bounds must be found anew.
        *scene.bounds_cache.lock() = None;
        applied
    }
}

/// Places `camera` by `world` (as the importer does), keeping its field of view; a singular
/// world leaves it where it was.
pub fn place_camera(camera: &mut Camera, world: &DMat4) {
    let eye = world.transform_point3(DVec3::ZERO);
    let forward = (-world.transform_vector3(DVec3::Z)).normalize_or_zero();
    let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
    if eye.is_finite() && forward != DVec3::ZERO && up != DVec3::ZERO {
        camera.eye = eye;
        camera.forward = forward;
        camera.up = up;
    }
}
