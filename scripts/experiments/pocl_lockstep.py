"""PoCL work-item-loop vectorisation toy (docs/benchmarks.md, "Fourth session"): a data-dependent
loop of table lookups run once per work item ("scalar") against the same loop cut into one step
per barrier-delimited round ("stepped"), which PoCL can vectorise across work items.
Needs pyopencl and numpy; LO/HI set the range of loop lengths."""
import pyopencl as cl, numpy as np, time, os
src = r'''
#define STEP(state, acc) { uint i = state % N; float4 b = tab[i]; acc += b.x*b.y - b.z; state = state*1664525u + 1013904223u + (uint)(acc>0.0f); }
kernel void scalar(global const float4* tab, uint N, global float* out, global const uint* len) {
  uint g = get_global_id(0); uint s = g*7919u; float acc = 0.0f;
  uint n = len[g];
  for (uint k = 0; k < n; ++k) STEP(s, acc)
  out[g] = acc;
}
kernel void stepped(global const float4* tab, uint N, global float* out, global const uint* len) {
  uint g = get_global_id(0); uint s = g*7919u; float acc = 0.0f;
  uint n = len[g]; uint k = 0;
  local int more;
  for (;;) {
    if (get_local_id(0) == 0) more = 0;
    barrier(CLK_LOCAL_MEM_FENCE);
    if (k < n) { STEP(s, acc) ++k; }
    if (k < n) more = 1;
    barrier(CLK_LOCAL_MEM_FENCE);
    if (!more) break;
  }
  out[g] = acc;
}
'''
ctx = cl.create_some_context(interactive=False); q = cl.CommandQueue(ctx)
prg = cl.Program(ctx, src).build()
G = 1<<18; N = 4096
tab = np.random.rand(N,4).astype(np.float32)
ln = np.random.randint(int(os.environ.get("LO","40")), int(os.environ.get("HI","60")), G).astype(np.uint32)
mf = cl.mem_flags
bt = cl.Buffer(ctx, mf.READ_ONLY|mf.COPY_HOST_PTR, hostbuf=tab)
bl = cl.Buffer(ctx, mf.READ_ONLY|mf.COPY_HOST_PTR, hostbuf=ln)
bo = cl.Buffer(ctx, mf.WRITE_ONLY, G*4)
for name in ["scalar","stepped"]:
  k = getattr(prg,name)
  for wg in [16, 64]:
    k(q,(G,),(wg,),bt,np.uint32(N),bo,bl); q.finish()
    t=time.time(); 
    for _ in range(3): k(q,(G,),(wg,),bt,np.uint32(N),bo,bl)
    q.finish(); dt=(time.time()-t)/3
    o = np.empty(G,np.float32); cl.enqueue_copy(q,o,bo)
    print(name, wg, f"{dt*1e3:.1f} ms", f"{G*ln.mean()/dt/1e6:.0f} Msteps/s", o[:2])
