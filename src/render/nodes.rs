//! The node arrays of the scene on the device: the forms (binary, wide) that the kernels in
//! use traverse, made from the host's acceleration structure, with the instances that name
//! their roots.

use super::{Accel, HostScene, NodeForms, Renderer};
use crate::bvh::WideBvh;
use crate::cl::types::*;
use crate::cl::{Buffer, ClError};

impl Renderer {
    /// Uploads `extra` node arrays beside those the kernels in use traverse
    /// ([`NodeForms::for_kernels`]: a CPU device's megakernel the wide nodes alone, a GPU's
    /// wavefront the binary ones), now for the loaded scene and at every load: for tests and
    /// `bench trace`, which trace through either array.
    pub fn set_node_forms(&mut self, extra: NodeForms) -> Result<(), ClError> {
        self.extra_forms = extra;
        self.ensure_node_forms()
    }

    /// The node arrays a scene load uploads.
    pub(super) fn node_forms(&self) -> NodeForms {
        NodeForms::for_kernels(self.megakernel).with(self.extra_forms)
    }

    /// Uploads the node arrays of the loaded scene that [`Renderer::node_forms`] asks for and
    /// it lacks (the kernels or the extra forms changed after the load), with the instances
    /// that name their roots.
    pub(crate) fn ensure_node_forms(&mut self) -> Result<(), ClError> {
        let want = self.node_forms();
        let Some((buffers, host)) = self.scene.as_mut() else {
            return Ok(());
        };
        let add = want.beyond(buffers.forms);
        if add == NodeForms::NONE {
            return Ok(());
        }
        let (nodes, wide) = device_nodes(host, add);
        if let Some(nodes) = nodes {
            buffers.nodes = Buffer::from_slice(&self.device, &nodes)?;
        }
        if let Some(wide) = wide {
            buffers.wide_nodes = Buffer::from_slice(&self.device, &wide)?;
        }
        buffers.forms = buffers.forms.with(add);
        if let Accel::TwoLevel(two) = &host.accel {
            let instances = host.layout.gpu_instances(two);
            buffers.instances.write_at(&self.device, 0, &instances)?;
        }
        Ok(())
    }
}

/// The device's node arrays (binary and wide, each a placeholder of one node unless `forms`
/// has it) and instances for `host`'s acceleration structure (the instances are a
/// placeholder when flat); fills `host.layout` for two levels.
pub(super) fn device_accel(
    host: &mut HostScene,
    forms: NodeForms,
) -> (Vec<DeviceBvhNode>, Vec<DeviceWideNode>, Vec<DeviceInstance>) {
    let (nodes, wide) = device_nodes(host, forms);
    let nodes = nodes.unwrap_or_else(|| vec![DeviceBvhNode::default()]);
    let wide = wide.unwrap_or_else(|| vec![DeviceWideNode::default()]);
    let instances = match &host.accel {
        Accel::Flat(_) => vec![DeviceInstance::default()],
        Accel::TwoLevel(two) => {
            // The small instances' world-space copies follow the meshes' triangles.
            let first = two.blases.iter().map(|b| b.len()).sum();
            host.triangles = host.layout.piece_copies(two, first);
            host.layout.gpu_instances(two)
        }
    };
    (nodes, wide, instances)
}

/// The node arrays that `forms` asks for of `host`'s acceleration structure; for two levels
/// each BLAS's root in every array made (in the binary array always: they are counted, not
/// made) goes to `host.layout`.
fn device_nodes(
    host: &mut HostScene,
    forms: NodeForms,
) -> (Option<Vec<DeviceBvhNode>>, Option<Vec<DeviceWideNode>>) {
    match &host.accel {
        Accel::Flat(bvh) => (
            forms.binary.then(|| bvh.nodes.clone()),
            forms.wide.then(|| WideBvh::collapse_for_cpu(bvh).nodes),
        ),
        Accel::TwoLevel(two) => {
            let nodes = if forms.binary {
                let (nodes, roots, _) = two.device_nodes();
                host.layout.roots = roots;
                Some(nodes)
            } else {
                host.layout.roots = two.device_roots();
                None
            };
            let wide = forms.wide.then(|| {
                let (wide, wide_roots) = two.device_wide_nodes();
                host.layout.wide_roots = wide_roots;
                wide
            });
            (nodes, wide)
        }
    }
}
