//! Loading a scene onto the device, in named steps: [`Renderer::plan`] builds the host side
//! (one flat BVH, or BLASes and a TLAS), [`scene_facts`] finds the kernel features it needs,
//! [`Renderer::ensure_program`] builds the kernels for them, and [`Renderer::upload`] makes the
//! device's buffers, checked first against the device's memory.

use super::nodes::device_accel;
use super::strategy::SceneFacts;
use super::{
    Accel, HostScene, Renderer, SceneStats, TEXTURE_BUDGET_BYTES, TexturePack, instancing, lights,
    samples_textures, upload,
};
use crate::cl::kernels::SceneBuffers;
use crate::cl::types::*;
use crate::cl::{Buffer, ClError, Device, KernelFeatures};
use crate::scene::{AlphaMode, Light, Material, Mesh, RenderFrame, Scene};
use std::sync::Arc;
use std::time::Instant;

/// A scene's host side as planned for the device.
struct Planned<'s> {
    /// The acceleration structure, triangles and shading data on the host.
    host: HostScene,
    /// Two levels: each BLAS's mesh in the plan's order, whose device structs are written at
    /// the upload; empty when flat.
    meshes: Vec<&'s Mesh>,
    /// Triangles left out for a non-finite or absurd vertex.
    dropped: usize,
    /// The meshes whose SAH BLASes build behind quick ones, where the plan made quick ones.
    behind: Option<Vec<Arc<Mesh>>>,
}

impl Planned<'_> {
    /// Two levels: the meshes' triangles (BLAS after BLAS), and whether any has tangents;
    /// (0, false) when flat.
    fn mesh_triangles(&self) -> (usize, bool) {
        match &self.host.accel {
            Accel::TwoLevel(two) => (
                two.blases.iter().map(|b| b.len()).sum(),
                self.meshes.iter().any(|m| !m.tangents.is_empty()),
            ),
            Accel::Flat(_) => (0, false),
        }
    }

    /// Whether some triangle has vertex colours: flat, the host scene's; two levels, a mesh's.
    fn colored(&self) -> bool {
        !self.host.colors.is_empty() || self.meshes.iter().any(|m| !m.colors.is_empty())
    }
}

/// The per-triangle buffers of a scene on the device.
struct TriangleBuffers {
    triangles: Buffer<DeviceTriangle>,
    shading: Buffer<DeviceTriShading>,
    uvs: Buffer<DeviceTriUvs>,
    tangents: Buffer<DeviceTriTangents>,
    colors: Buffer<DeviceTriColors>,
}

/// The per-triangle buffers of a scene replaced, to be written again in place.
type OldTriangleBuffers = (
    Option<Buffer<DeviceTriangle>>,
    Option<Buffer<DeviceTriShading>>,
    Option<Buffer<DeviceTriUvs>>,
    Option<Buffer<DeviceTriTangents>>,
    Option<Buffer<DeviceTriColors>>,
);

impl Renderer {
    /// The scene's textures packed for the device. An animated scene's pack is kept and taken
    /// again while its images, their uses and the budget stay the same: packing builds every
    /// mip chain (80–190 ms a frame for the Fox's one 1024² texture on 2 cores, 2026-12-07),
    /// while a pose changes no texture. Other scenes are packed each load and the texels
    /// freed after the upload.
    fn texture_pack(&mut self, scene: &Scene) -> Arc<TexturePack> {
        use std::hash::{Hash, Hasher};
        let budget = self.texture_budget();
        if scene.animation.clips.is_empty() {
            self.texture_cache = None;
            return Arc::new(TexturePack::new(scene, budget));
        }
        let mut h = std::collections::hash_map::DefaultHasher::new();
        budget.hash(&mut h);
        for image in &scene.images {
            Arc::as_ptr(image).hash(&mut h);
        }
        format!("{:?}", scene.texture_refs).hash(&mut h);
        let key = h.finish();
        if let Some((k, pack)) = &self.texture_cache
            && *k == key
        {
            return Arc::clone(pack);
        }
        let pack = Arc::new(TexturePack::new(scene, budget));
        self.texture_cache = Some((key, Arc::clone(&pack)));
        pack
    }

    /// [`Renderer::load_scene_in`] with BLASes made as `how` says; with quick ones, their SAH
    /// BLASes start building behind them. `reuse`: the buffers of the scene replaced, written
    /// again in place where the size is the same.
    pub(super) fn load_with(
        &mut self,
        scene: &Scene,
        lights: &[Light],
        space: RenderFrame,
        how: instancing::Blases,
        reuse: Option<SceneBuffers>,
    ) -> Result<SceneStats, ClError> {
        let _memory = crate::cl::kernels::OpeningMemory::begin();
        self.sah = None;
        self.sah_waiting = None;
        let t = Instant::now();
        let materials: Vec<_> = scene.materials.iter().map(|m| space.material(m)).collect();
        let mut planned = self.plan(scene, &space, &materials, how);
        let bvh_build_ms = t.elapsed().as_secs_f64() * 1e3;

        let t = Instant::now();
        planned.host.space = space;
        planned
            .host
            .scale_emitter_power(&lights::emissive_texture_means(scene));
        self.facts = scene_facts(scene, &planned);
        let pack = self.texture_pack(scene);
        let kernel_build_ms = self.ensure_program()?;
        self.lights = lights.to_vec();
        let (glights, cdf) = self.light_table(&planned.host);
        log::debug!(
            "kernels, textures, lights: {:.0} ms",
            t.elapsed().as_secs_f64() * 1e3
        );
        let buffers = self.upload(&mut planned, &materials, &pack, (&glights, &cdf), reuse, t)?;
        let (pack_textures, pack_bytes, pack_max_side) =
            (pack.textures.len(), pack.bytes(), pack.max_side);
        drop(pack);
        self.light_count = glights.len() as u32;
        self.update_env_info(&glights);
        let Planned {
            host,
            dropped,
            behind,
            ..
        } = planned;
        let (meshes, instances) = host.accel.instancing();
        let mut stats = SceneStats {
            triangles: host.triangle_count(),
            nodes: host.accel.node_count(),
            sah_cost: host.accel.sah_cost(),
            bvh_build_ms,
            kernel_build_ms,
            kernels_built: kernel_build_ms > 0.0,
            upload_ms: t.elapsed().as_secs_f64() * 1e3 - kernel_build_ms,
            textures: pack_textures,
            texture_bytes: pack_bytes,
            texture_max_side: pack_max_side,
            dropped_triangles: dropped,
            bvh: host.accel.name(),
            meshes,
            instances,
            device_bytes: buffers.bytes(),
            written_bytes: buffers.bytes(),
        };
        self.scene = Some((buffers, host));
        // The SAH BLASes start once the quick scene's first image is in ([`Renderer::swap_in_sah`]),
        // not to slow its upload nor that image.
        self.sah_waiting = behind;
        if let Some(c) = self.world_camera.clone() {
            self.set_camera(&c)?;
        }
        stats.kernel_build_ms += self.prime_megakernel()?;
        self.reset()?;
        Ok(stats)
    }

    /// Plans the scene's host side: BLASes of its meshes and a TLAS over their instances where
    /// the BVH choice and the device's rule take two levels (quick BLASes first as `how` says),
    /// else one flat BVH over every visible triangle.
    fn plan<'s>(
        &self,
        scene: &'s Scene,
        space: &RenderFrame,
        materials: &[Material],
        how: instancing::Blases,
    ) -> Planned<'s> {
        let t = Instant::now();
        let mut rule = if self.device.is_cpu() {
            instancing::AUTO_CPU
        } else {
            instancing::AUTO_GPU
        };
        if let Some(small_mesh) = self.small_mesh {
            rule.small_mesh = small_mesh;
        }
        let Some(plan) = instancing::plan(scene, space, self.bvh_choice, rule, how) else {
            let (host, dropped) = HostScene::flatten(scene, space, materials);
            return Planned {
                host,
                meshes: vec![],
                dropped,
                behind: None,
            };
        };
        log::debug!(
            "BLASes and TLAS in {:.0} ms",
            t.elapsed().as_secs_f64() * 1e3
        );
        let behind = plan.quick.then(|| Self::sah_meshes(scene, &plan));
        // Two levels: nothing is flattened; each mesh goes to the device once.
        let meshes: Vec<&Mesh> = plan
            .mesh_objects
            .iter()
            .map(|&o| scene.objects[o as usize].mesh.as_ref())
            .collect();
        let mut host = HostScene::two_level(
            plan.two,
            &meshes,
            materials,
            upload::render_middle(scene, space),
        );
        host.layout.objects = plan.objects;
        Planned {
            host,
            meshes,
            dropped: 0,
            behind,
        }
    }

    /// Texel memory for a scene's textures: [`TEXTURE_BUDGET_BYTES`], or less where the
    /// device's largest buffer is smaller.
    fn texture_budget(&self) -> usize {
        self.device
            .device
            .max_mem_alloc_size()
            .map_or(TEXTURE_BUDGET_BYTES, |m| {
                (m as usize).min(TEXTURE_BUDGET_BYTES)
            })
    }

    /// Makes the device's buffers of the planned scene: the node arrays the kernels traverse
    /// and the instances, the per-triangle data, textures, materials and `lights` (the light
    /// table and its CDF). Fails before any allocation when they cannot fit the device.
    fn upload(
        &self,
        planned: &mut Planned,
        materials: &[Material],
        pack: &TexturePack,
        (glights, cdf): (&[DeviceLight], &[f32]),
        reuse: Option<SceneBuffers>,
        since: Instant,
    ) -> Result<SceneBuffers, ClError> {
        let forms = self.node_forms();
        let (mesh_triangles, mesh_tangents) = planned.mesh_triangles();
        let mesh_colors = !planned.meshes.is_empty() && planned.colored();
        let host = &mut planned.host;
        host.layout.mesh_tangents = mesh_tangents;
        let (nodes, wide_nodes, instances) = device_accel(host, forms);
        log::debug!(
            "device nodes: {:.0} ms",
            since.elapsed().as_secs_f64() * 1e3
        );
        // Triangles and shading data are the device's alone (picking keeps each flat triangle's
        // object, `HostScene::objects`). The flat form's leave the host scene, and each large
        // host array is freed as soon as its buffer is made, so that the two copies (host
        // memory either way with a CPU device) are not all held at once. Two levels write
        // every mesh's straight into the buffers (`HostScene::fill_meshes`), no host copy made;
        // their host triangles are the small instances' world-space copies, which follow the
        // meshes' in the device triangles.
        let triangles = std::mem::take(&mut host.triangles);
        let shading = std::mem::take(&mut host.shading);
        let uvs = std::mem::take(&mut host.uvs);
        let tangents = std::mem::take(&mut host.tangents);
        let colors = std::mem::take(&mut host.colors);
        let color_count = if mesh_colors { mesh_triangles } else { 0 } + colors.len();
        let tangent_count = if mesh_tangents { mesh_triangles } else { 0 } + tangents.len();
        // Texture coordinates only when some material samples a texture (a superset of the
        // kernels' `HAS_TEXTURES`, which alone reads them); else a placeholder.
        let mesh_uvs = samples_textures(materials);
        let uv_count = if mesh_uvs { mesh_triangles } else { 0 } + uvs.len();
        let lengths = (
            mesh_triangles + triangles.len(),
            mesh_triangles + shading.len(),
            tangent_count.max(1),
            uv_count.max(1),
            color_count.max(1),
        );
        // Two levels trace the meshes' object-space triangles in `triangles`: the separate
        // object-triangle buffer is a placeholder either way.
        let object_tris = [DeviceTriangle::default()];
        let bytes = |n: usize, size: usize| n.max(1) * size;
        let sizes = [
            ("BVH nodes", std::mem::size_of_val(nodes.as_slice())),
            (
                "wide BVH nodes",
                std::mem::size_of_val(wide_nodes.as_slice()),
            ),
            (
                "triangles",
                lengths.0 * std::mem::size_of::<DeviceTriangle>(),
            ),
            ("instances", std::mem::size_of_val(instances.as_slice())),
            (
                "shading",
                lengths.1 * std::mem::size_of::<DeviceTriShading>(),
            ),
            ("uvs", lengths.3 * std::mem::size_of::<DeviceTriUvs>()),
            (
                "tangents",
                lengths.2 * std::mem::size_of::<DeviceTriTangents>(),
            ),
            ("colors", lengths.4 * std::mem::size_of::<DeviceTriColors>()),
            ("texels", bytes(pack.texels.len(), 4)),
        ];
        log::debug!(
            "device buffers: {}",
            sizes
                .iter()
                .map(|(name, b)| format!("{name} {:.1} MB", *b as f64 / 1e6))
                .collect::<Vec<_>>()
                .join(", ")
        );
        fits_device(
            &sizes,
            self.device.device.global_mem_size().ok(),
            self.device.device.max_mem_alloc_size().ok(),
        )
        .map_err(ClError::Device)?;
        // The large buffers of the scene replaced (a swap to SAH BLASes), written again in
        // place where the size is the same: no fresh memory to fault in.
        let (old_nodes, old_wide, old_instances, old) = match reuse {
            Some(b) => (
                Some(b.nodes),
                Some(b.wide_nodes),
                Some(b.instances),
                (
                    Some(b.triangles),
                    Some(b.shading),
                    Some(b.uvs),
                    Some(b.tangents),
                    Some(b.colors),
                ),
            ),
            None => Default::default(),
        };
        let device = &self.device;
        let nodes_buffer = put(device, old_nodes, &nodes)?;
        drop(nodes);
        let wide_buffer = put(device, old_wide, &wide_nodes)?;
        drop(wide_nodes);
        let per_triangle = match &host.accel {
            Accel::Flat(_) => {
                flat_buffers(device, old, (triangles, shading, uvs, tangents, colors))?
            }
            Accel::TwoLevel(two) => {
                let (o_tri, o_sh, o_uv, o_tan, o_col) = old;
                let mut shading_buffer = sized(device, o_sh, lengths.1)?;
                let mut uvs_buffer = sized(device, o_uv, lengths.3)?;
                let mut tangents_buffer = sized(device, o_tan, lengths.2)?;
                let mut colors_buffer = sized(device, o_col, lengths.4)?;
                let mut triangles_buffer = sized(device, o_tri, lengths.0)?;
                let n = mesh_triangles;
                let meshes = &planned.meshes;
                triangles_buffer.fill_mapped(device, |tris| {
                    shading_buffer.fill_mapped(device, |sh| {
                        uvs_buffer.fill_mapped(device, |uv| {
                            tangents_buffer.fill_mapped(device, |tan| {
                                colors_buffer.fill_mapped(device, |col| {
                                    let tan_out = &mut tan[..if mesh_tangents { n } else { 0 }];
                                    let uv_out = &mut uv[..if mesh_uvs { n } else { 0 }];
                                    let col_out = &mut col[..if mesh_colors { n } else { 0 }];
                                    let out =
                                        (&mut tris[..n], &mut sh[..n], uv_out, tan_out, col_out);
                                    HostScene::fill_meshes(two, meshes, materials, out);
                                    tris[n..].copy_from_slice(&triangles);
                                    if !mesh_tangents {
                                        tan.fill(DeviceTriTangents::default());
                                    }
                                    if !mesh_uvs {
                                        uv.fill(DeviceTriUvs::default());
                                    }
                                    if !mesh_colors {
                                        col.fill(DeviceTriColors::default());
                                    }
                                })
                            })
                        })
                    })
                })?????;
                TriangleBuffers {
                    triangles: triangles_buffer,
                    shading: shading_buffer,
                    uvs: uvs_buffer,
                    tangents: tangents_buffer,
                    colors: colors_buffer,
                }
            }
        };
        let instances_buffer = put(device, old_instances, &instances)?;
        let buffers = SceneBuffers {
            forms,
            nodes: nodes_buffer,
            wide_nodes: wide_buffer,
            triangles: per_triangle.triangles,
            instances: instances_buffer,
            object_triangles: Buffer::from_slice(device, &object_tris)?,
            shading: per_triangle.shading,
            uvs: per_triangle.uvs,
            tangents: per_triangle.tangents,
            colors: per_triangle.colors,
            tex_refs: Buffer::from_slice(device, &pack.refs)?,
            textures: Buffer::from_slice(device, &pack.textures)?,
            texels: Buffer::from_slice(device, &pack.texels)?,
            materials: Buffer::from_slice(device, &host.materials)?,
            lights: Buffer::from_slice(device, glights)?,
            light_cdf: Buffer::from_slice(device, cdf)?,
        };
        drop(instances);
        Ok(buffers)
    }
}

/// A flat scene's per-triangle host arrays: triangles, shading, texture coordinates, tangents
/// and colours.
type FlatArrays = (
    Vec<DeviceTriangle>,
    Vec<DeviceTriShading>,
    Vec<DeviceTriUvs>,
    Vec<DeviceTriTangents>,
    Vec<DeviceTriColors>,
);

/// A flat scene's per-triangle buffers from its host arrays (triangles, shading, texture
/// coordinates, tangents, colours; the last three a placeholder of one when empty), each array freed as
/// soon as its buffer is made; `old`'s buffers written again where the length is the same.
fn flat_buffers(
    device: &Device,
    (o_tri, o_sh, o_uv, o_tan, o_col): OldTriangleBuffers,
    (triangles, shading, mut uvs, mut tangents, mut colors): FlatArrays,
) -> Result<TriangleBuffers, ClError> {
    let shading_buffer = put(device, o_sh, &shading)?;
    drop(shading);
    if uvs.is_empty() {
        uvs.push(DeviceTriUvs::default());
    }
    let uvs_buffer = put(device, o_uv, &uvs)?;
    drop(uvs);
    if tangents.is_empty() {
        tangents.push(DeviceTriTangents::default());
    }
    let tangents_buffer = put(device, o_tan, &tangents)?;
    drop(tangents);
    if colors.is_empty() {
        colors.push(DeviceTriColors::default());
    }
    let colors_buffer = put(device, o_col, &colors)?;
    drop(colors);
    let triangles_buffer = put(device, o_tri, &triangles)?;
    Ok(TriangleBuffers {
        triangles: triangles_buffer,
        shading: shading_buffer,
        uvs: uvs_buffer,
        tangents: tangents_buffer,
        colors: colors_buffer,
    })
}

/// The kernel strategy's facts of a planned scene: the features it needs (without the
/// environment map's, which [`Renderer::ensure_program`] adds), its triangles and its flat
/// BVH's largest leaf.
fn scene_facts(scene: &Scene, planned: &Planned) -> SceneFacts {
    let host = &planned.host;
    let (_, mesh_tangents) = planned.mesh_triangles();
    let features = KernelFeatures {
        two_level: matches!(host.accel, Accel::TwoLevel(_)),
        triangle_pieces: matches!(&host.accel, Accel::TwoLevel(t) if t.has_small_meshes()),
        // The kernels read vertex colours exactly when the upload made them.
        vertex_colors: planned.colored(),
        ..scene_features(
            scene,
            !host.emissive.is_empty(),
            !host.tangents.is_empty() || mesh_tangents,
        )
    };
    SceneFacts {
        features,
        triangles: host.triangles.len(),
        largest_leaf: match &host.accel {
            Accel::Flat(bvh) => bvh.largest_leaf(),
            Accel::TwoLevel(_) => 0,
        },
    }
}

/// The kernel features a scene needs; `triangle_lights` and `tangents` come from its upload
/// (emissive triangles with an area, tangents for normal maps).
pub(super) fn scene_features(
    scene: &Scene,
    triangle_lights: bool,
    tangents: bool,
) -> KernelFeatures {
    // Only the materials some triangle uses (the importer's default material often is not).
    let in_use = scene.used_materials();
    let materials = || {
        scene
            .materials
            .iter()
            .zip(&in_use)
            .filter(|(_, u)| **u)
            .map(|(m, _)| m)
    };
    let used = |f: &dyn Fn(&crate::scene::Material) -> bool| materials().any(f);
    KernelFeatures {
        triangle_lights,
        textures: used(&|m| m.textures.any()),
        normal_maps: used(&|m| m.textures.normal_mapped()) && tangents,
        alpha: used(&|m| m.alpha != AlphaMode::Opaque),
        single_sided: used(&|m| !m.double_sided),
        // Predicted from the visible meshes; `scene_facts` takes the upload's own answer.
        vertex_colors: scene
            .objects
            .iter()
            .any(|o| o.visible && !o.mesh.colors.is_empty()),
        transmission: used(&|m| m.transmission > 0.0),
        env_map: false,
        two_level: false,
        triangle_pieces: false,
        thin_walls: used(&|m| m.transmission > 0.0 && m.thickness <= 0.0),
        unlit: used(&|m| m.unlit),
        clearcoat: used(&|m| m.clearcoat > 0.0),
        sheen: used(&|m| m.sheen_color.iter().any(|&c| c > 0.0)),
        diffuse_transmission: used(&|m| m.diffuse_transmission > 0.0),
        iridescence: used(&|m| m.iridescence > 0.0),
        anisotropy: used(&|m| m.anisotropy > 0.0),
        dispersion: used(&|m| m.is_dispersive()),
        tangents: used(&|m| m.anisotropy > 0.0) && tangents,
        lambert_only: materials().all(|m| m.is_lambertian()),
        small_scene: 0,
        lanes: false,
        lanes_shade: false,
        lanes_small: false,
        lanes_gathers: false,
        aovs: false,
    }
}

/// A buffer holding `data`: `old` written again when it has `data`'s length, else a new one
/// (`old` freed first).
fn put<T: bytemuck::Pod>(
    device: &Device,
    old: Option<Buffer<T>>,
    data: &[T],
) -> Result<Buffer<T>, ClError> {
    match old {
        Some(mut b) if b.len() == data.len() && !data.is_empty() => {
            b.write(device, data)?;
            Ok(b)
        }
        old => {
            drop(old);
            Buffer::from_slice(device, data)
        }
    }
}

/// A buffer of `len` elements: `old` when it has that length (its memory written again in
/// place, no fresh pages to fault in), else a new one (contents undefined either way).
fn sized<T: bytemuck::Pod>(
    device: &Device,
    old: Option<Buffer<T>>,
    len: usize,
) -> Result<Buffer<T>, ClError> {
    match old {
        Some(b) if b.len() == len => Ok(b),
        old => {
            drop(old);
            Buffer::new(device, len)
        }
    }
}

/// Checks before any allocation that the scene's buffers fit the device: their sum against
/// `CL_DEVICE_GLOBAL_MEM_SIZE` (`global`) and each against `CL_DEVICE_MAX_MEM_ALLOC_SIZE`
/// (`max_alloc`), so that a scene too large fails with one clear line instead of an allocation
/// error halfway through the upload.
fn fits_device(
    buffers: &[(&str, usize)],
    global: Option<u64>,
    max_alloc: Option<u64>,
) -> Result<(), String> {
    let gb = |b: u64| b as f64 / 1e9;
    let total: usize = buffers.iter().map(|(_, b)| b).sum();
    if let Some(global) = global
        && total as u64 > global
    {
        return Err(format!(
            "the scene needs {:.2} GB of device memory and the device has {:.2} GB \
             (an instanced scene takes less with --bvh two-level)",
            gb(total as u64),
            gb(global)
        ));
    }
    if let Some(max) = max_alloc
        && let Some((name, b)) = buffers.iter().find(|(_, b)| *b as u64 > max)
    {
        return Err(format!(
            "the scene's {name} need a {:.2} GB buffer and the device allows {:.2} GB in one",
            gb(*b as u64),
            gb(max)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::{fits_device, scene_features};
    use crate::scene::{Material, Mesh, Object, Scene};
    use glam::{DMat4, Vec3};

    /// One triangle per material index in `uses`, of a scene with `materials`.
    fn scene_using(materials: Vec<Material>, uses: &[u32]) -> Scene {
        let mut mesh = Mesh::default();
        for &m in uses {
            let base = mesh.positions.len() as u32;
            mesh.positions.extend([Vec3::ZERO, Vec3::X, Vec3::Y]);
            mesh.indices.push([base, base + 1, base + 2]);
            mesh.materials.push(m);
        }
        let object = Object {
            name: "o".into(),
            world_from_object: DMat4::IDENTITY,
            visible: true,
            mesh: mesh.into(),
        };
        Scene {
            materials,
            objects: vec![object],
            ..Scene::default()
        }
    }

    #[test]
    fn lambert_only_looks_at_the_materials_in_use() {
        let lambert = Material {
            specular_factor: 0.0,
            ..Material::default()
        };
        let glossy = Material::default(); // the importer's fallback: a specular layer
        let features = |uses: &[u32]| {
            scene_features(
                &scene_using(vec![lambert.clone(), glossy.clone()], uses),
                false,
                false,
            )
        };
        assert!(
            features(&[0, 0]).lambert_only,
            "the unused glossy material does not count"
        );
        assert!(!features(&[0, 1]).lambert_only);
        let metal = Material {
            metallic: 1.0,
            ..lambert.clone()
        };
        let scene = scene_using(vec![lambert.clone(), metal], &[0, 1]);
        assert!(!scene_features(&scene, false, false).lambert_only);
    }

    #[test]
    fn scenes_too_large_for_the_device_are_refused_with_a_reason() {
        let buffers = [("triangles", 600), ("shading", 500)];
        assert!(fits_device(&buffers, Some(2000), Some(1000)).is_ok());
        assert!(fits_device(&buffers, None, None).is_ok());
        let total = fits_device(&buffers, Some(1000), Some(1000)).unwrap_err();
        assert!(total.contains("device memory"), "{total}");
        let one = fits_device(&buffers, Some(2000), Some(550)).unwrap_err();
        assert!(one.contains("triangles need"), "{one}");
    }
}
