// Node visits per ray of the binary BVH collapsed to 2, 4, 8 and 16 children (host, nearest first),
// for random rays inside a scene. Run: cp scripts/experiments/widecount.rs examples/ &&
// cargo run --release --example widecount -- SCENE.glb
use glam::Vec3;
use penumbra::bvh::{Child, build};
fn collapse(bvh: &penumbra::bvh::Bvh, width: usize) -> Vec<Vec<(penumbra::bvh::Aabb, Child)>> {
    let mut nodes: Vec<Vec<(penumbra::bvh::Aabb, Child)>> = vec![vec![]];
    let mut work = vec![(0u32, 0usize)];
    while let Some((b, w)) = work.pop() {
        let mut slots: Vec<_> = (0..2).map(|s| bvh.child(b, s)).collect();
        while slots.len() < width {
            let Some((i, n)) = slots.iter().enumerate().filter_map(|(i, s)| match s.1 { Child::Node(n) => Some((i, n, s.0.area())), _ => None }).max_by(|a, b| a.2.total_cmp(&b.2)).map(|(i, n, _)| (i, n)) else { break };
            slots.swap_remove(i);
            for s in 0..2 { slots.push(bvh.child(n, s)); }
        }
        let mut out = vec![];
        for (bx, c) in slots {
            match c { Child::Node(n) => { let idx = nodes.len(); nodes.push(vec![]); work.push((n, idx)); out.push((bx, Child::Node(idx as u32))); } l => out.push((bx, l)) }
        }
        nodes[w] = out;
    }
    nodes
}
fn slab(b: &penumbra::bvh::Aabb, o: Vec3, inv: Vec3, tmax: f32) -> Option<f32> {
    let t0 = (b.min - o) * inv; let t1 = (b.max - o) * inv;
    let near = t0.min(t1).max_element().max(0.0); let far = t0.max(t1).min_element();
    (near <= far && near < tmax).then_some(near)
}
fn tri(o: Vec3, d: Vec3, t: &[Vec3; 3]) -> Option<f32> {
    let e1 = t[1] - t[0]; let e2 = t[2] - t[0]; let p = d.cross(e2); let det = e1.dot(p);
    if det.abs() < 1e-12 { return None; } let inv = 1.0 / det; let s = o - t[0]; let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) { return None; } let q = s.cross(e1); let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 { return None; } let tt = e2.dot(q) * inv; (tt > 1e-4).then_some(tt)
}
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let scene = penumbra::scene::load_or_bundled(Some(std::path::Path::new(&path))).unwrap();
    let tris: Vec<[Vec3; 3]> = scene.world_triangles().iter().map(|t| t.v).collect();
    let bvh = build(&tris);
    let ordered: Vec<[Vec3; 3]> = bvh.tri_indices.iter().map(|&i| tris[i as usize]).collect();
    let b = scene.bounds(); let (lo, hi) = (b.min.as_vec3(), b.max.as_vec3());
    for width in [2usize, 4, 8, 16] {
        let nodes = collapse(&bvh, width);
        let mut s = 7u64; let mut rnd = move || { s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407); (s >> 40) as f32 / (1u64 << 24) as f32 };
        let (mut visits, mut tests, mut hits) = (0u64, 0u64, 0u64); let n = 20000;
        for _ in 0..n {
            let o = lo + (hi - lo) * Vec3::new(rnd(), rnd(), rnd()) * 0.9 + (hi - lo) * 0.05;
            let d = (Vec3::new(rnd(), rnd(), rnd()) - 0.5).normalize(); let inv = d.recip();
            let mut tmax = f32::INFINITY; let mut stack = vec![(0u32, 0.0f32)];
            while let Some((node, dn)) = stack.pop() {
                if dn >= tmax { continue; } visits += 1;
                let mut kids: Vec<(f32, Child)> = nodes[node as usize].iter().filter_map(|(bx, c)| slab(bx, o, inv, tmax).map(|t| (t, *c))).collect();
                kids.sort_by(|a, b| a.0.total_cmp(&b.0));
                let mut interior = vec![];
                for (t, c) in kids { match c { Child::Leaf { first, count } => { if t < tmax { for p in first..first + count { tests += 1; if let Some(th) = tri(o, d, &ordered[p as usize]) { if th < tmax { tmax = th; } } } } } Child::Node(m) => interior.push((m, t)) } }
                for &(m, t) in interior.iter().rev() { stack.push((m, t)); }
            }
            hits += tmax.is_finite() as u64;
        }
        println!("width {width}: nodes {} visits/ray {:.2} tests/ray {:.2} hits {}", nodes.len(), visits as f64 / n as f64, tests as f64 / n as f64, hits);
    }
}
