// The path tracer as one kernel with its rays in vector lanes, for CPU devices with AVX-512 or
// AVX2 (MEGA_LANES, set by the host: strategy::kernel_strategy in src/render/strategy.rs):
// megakernel.cl's estimator from the same random numbers, with the paths of a tile of pixels
// walking the 4-wide BVH together, a ray a lane (traverse_lanes.h) or as packets (traverse_packet.h), and with
// LANES_SHADE their vertices shaded in batches (shade_lanes.h). Each pixel sums its samples in
// megakernel.cl's order: the same image.

#include "shared/types.h"
#include "shared/traverse.h"
#include "cpu/traverse_lanes.h"
#include "cpu/traverse_packet.h"
#include "shared/path.h"
#include "cpu/shade_lanes.h"
#include "cpu/megakernel.h"

#ifdef MEGA_LANES
#ifdef AOVS
// The lanes record no guide buffers: with AOVs the host builds the one-path-at-a-time
// megakernel (src/render/strategy.rs).
#error "MEGA_LANES with AOVS"
#endif
// With MEGA_LANES a work item renders a square of LANES_TILE² pixels in two shapes of walk:
//   - a chunk of a pixel's samples (sixteen at a time) or, below sixteen samples, of a 4×4
//     block's, starts together: their camera rays walk the tree as one packet
//     (traverse_packet.h), their first vertices are shaded (by shade_vertex, or together by
//     lanes_shade), and their light samples, which start close together and go to one light,
//     walk as a packet too;
//   - the paths that go on take turns in sixteen lanes (traverse_lanes.h), one ray a lane, whose
//     rays walk together, each at its own node: when some are done, their vertices are shaded
//     (at once, or with LANES_SHADE in batches of sixteen, shade_lanes.h), the light sample of
//     each walks next (an any-hit ray), then the path's next ray; a lane whose ray is done takes
//     the next ray waiting, or the next path of a chunk.
// A chunk's results wait in its record until all its paths are done; then they are added to
// their pixels' film sums in sample order, and a pixel has one chunk in flight at a time, so
// each pixel sums its samples in the order megakernel.cl's one-pixel kernel does: the same image,
// bit for bit (but for rays meeting two triangles at the same distance).
// Paths in flight: one a lane, or with vertices shaded in batches (shade_lanes.h) twice as many,
// so that the lanes walk other paths' rays while a batch fills (-DMEGA_SLOTS=n measures others:
// on the room, 1.5 and 3 times the lanes ran 3.4 % and 0.6 % more instructions).
#ifndef MEGA_SLOTS
#ifdef LANES_SHADE
#define MEGA_SLOTS (2 * LANES)
#else
#define MEGA_SLOTS LANES
#endif
#endif
// Records: a chunk a path in flight, and the queue's, cannot starve.
#define MEGA_CHUNKS (MEGA_SLOTS + 4)

typedef struct {
    uint pixel[LANES];    // entry e's pixel (a pixel's entries follow each other, in sample order)
    float3 result[LANES];  // entry e's radiance, once its path is done
    uint escaped;          // bit e: entry e's camera ray escaped (PATH_ESCAPED)
    uint even;             // bit e: entry e's sample index is even (adaptive.h's half buffer)
    uint rays[LANES];      // entry e's rays traced so far (adaptive.h's ray count)
    uint count;            // entries
    uint remaining;        // paths not yet done: 0 when the record is not in flight
    uint next_sample;      // one pixel a chunk: the pixel's next sample to start
    bool more;             // one pixel a chunk: the pixel has samples left (the record is kept)
} MegaChunk;

// A work item's pixels, chunks, and the paths started but not yet in a lane.
typedef struct {
    MegaChunk chunk[MEGA_CHUNKS];
    PathState queued[LANES];
    uint queued_chunk[LANES], queued_entry[LANES];
    uint queue_head, queue_end;
    uint tile_x, tile_y, tile_w, tile_h;
    uint next_pixel;  // of the tile, in 4×4 blocks
    uint extension_rays, shadow_rays, nonfinite;
    global float4* halves;  // adaptive sampling's film (shared/adaptive.h)
    global uint* state;
    global uint* rays;
} MegaWork;

// The tile's pixel `i` in the order of 4×4 blocks (16 of them, row by row), or -1 outside the
// image.
inline int mega_tile_pixel(const MegaWork* W, const DeviceFrame* frame, uint i) {
    uint x = i / 16u % 4u * 4u + i % 4u;
    uint y = i / 64u * 4u + i % 16u / 4u;
    if (x >= W->tile_w || y >= W->tile_h) return -1;
    return (int)((W->tile_y + y) * frame->width + W->tile_x + x);
}

// A record's chunk done: its results added to the film, pixel by pixel in sample order.
inline void mega_chunk_done(MegaWork* W, const DeviceFrame* frame, global ulong4* film,
                            MegaChunk* c) {
    uint e = 0u;
    while (e < c->count) {
        uint p = c->pixel[e];
        ulong4 f = film[p];
        ulong3 sum = f.xyz;
        uint counted = 0u, samples = 0u, traced = 0u;
        float3 even = (float3)(0.0f);
        uint evens = 0u;
        for (; e < c->count && c->pixel[e] == p; ++e, ++samples) {
            traced += c->rays[e];
            mega_add_sample(c->result[e], ((c->escaped >> e) & 1u) != 0u, &sum, &counted,
                            &W->nonfinite);
            // The index's parity from the chunk's bit: 0 for even, 1 for odd.
            half_add(c->result[e], ((c->even >> e) & 1u) ^ 1u, &even, &evens);
        }
        uint n = frame->background == BACKGROUND_ENV ? samples : counted;
        film[p] = (ulong4)(sum, f.w + n);
        if (frame->adaptive != 0u) {
            half_store(W->halves, W->state, p, even, evens, samples);
            if (frame->adaptive == ADAPTIVE_COST) W->rays[p] += traced;
        }
    }
}

// A path done: its radiance into its chunk's record.
inline void mega_path_done(MegaWork* W, const DeviceFrame* frame, global ulong4* film, uint chunk,
                           uint entry, const PathState* s) {
    MegaChunk* c = &W->chunk[chunk];
    c->result[entry] = s->radiance;
    if (s->flags & PATH_ESCAPED) c->escaped |= 1u << entry;
    if (--c->remaining == 0u) mega_chunk_done(W, frame, film, c);
}

// Starts the next chunk: its camera rays as a packet, their vertices shaded, their light
// samples as a packet; the paths that go on are queued. Returns false when no chunk can start
// (the tile's pixels all started, and no pixel with samples left is free of chunks in flight).
inline bool mega_chunk_start(MegaWork* W, const DeviceFrame* frame, const DeviceCamera* camera,
                             const ShadeScene* sc, global const DeviceWideNode* nodes,
                             global const DeviceInstance* instances,
                             global const DeviceTriangle* object_tris, global ulong4* film,
                             volatile global uint* overflow) {
    uint spp = frame->samples_in_wave;
    // A pixel with samples left whose last chunk is done; else a free record for new pixels.
    int r = -1, free_ = -1;
    for (int i = 0; i < MEGA_CHUNKS; ++i) {
        MegaChunk* c = &W->chunk[i];
        if (c->remaining != 0u) continue;
        if (c->more) {
            r = i;
            break;
        }
        if (free_ < 0) free_ = i;
    }
    uint sample0[LANES];
    MegaChunk* c;
    if (r >= 0) {
        c = &W->chunk[r];
        c->count = min(spp - c->next_sample, (uint)LANES);
        for (uint e = 0u; e < c->count; ++e) sample0[e] = c->next_sample + e;
        for (uint e = 1u; e < c->count; ++e) c->pixel[e] = c->pixel[0];
    } else {
        if (free_ < 0) return false;
        r = free_;
        c = &W->chunk[r];
        // The next pixel (all of its samples, or the first sixteen), or as many pixels as
        // sixteen lanes take all the samples of.
        uint pixels = spp >= (uint)LANES ? 1u : (uint)LANES / spp;
        c->count = 0u;
        for (uint k = 0u; k < pixels && W->next_pixel < LANES_TILE * LANES_TILE;) {
            int p = mega_tile_pixel(W, frame, W->next_pixel++);
            if (p < 0 || pixel_converged(frame, W->state, (uint)p)) continue;
            for (uint j = 0u; j < min(spp, (uint)LANES); ++j) {
                c->pixel[c->count] = (uint)p;
                sample0[c->count++] = j;
            }
            ++k;
        }
        if (c->count == 0u) return false;
        c->next_sample = 0u;
    }
    c->next_sample += spp >= (uint)LANES ? c->count : spp;
    c->more = c->next_sample < spp;
    c->escaped = 0u;
    c->even = 0u;
    for (uint e = 0u; e < c->count; ++e) {
        c->even |= (uint)(((frame->first_sample + sample0[e]) & 1u) == 0u) << e;
        c->rays[e] = 1u;  // its camera ray
    }
    c->remaining = c->count;
    uint n = c->count;
    W->extension_rays += n;
    Packet P;
    LanesRays R;
    lanes_rays_init(&R);
    PathState* s = W->queued;
    for (uint e = 0u; e < n; ++e) {
        s[e] = camera_path(frame, camera, c->pixel[e], frame->first_sample + sample0[e]);
        packet_take_ray(&P, &R, (int)e, s[e].origin, s[e].direction, INFINITY);
    }
    packet_set_rays(&P, &R);
    vint lanes = LANE_IDS < (vint)((int)n);
    packet_walk(&P, lanes, false, nodes, sc->tris, &sc->surf, overflow);
    DeviceHit hit[LANES];
    for (uint e = 0u; e < n; ++e) {
        hit[e] = packet_hit(&P, (int)e);
#ifdef HAS_SINGLE_SIDED
        hit[e] = camera_hit_wide(nodes, sc->tris, instances, object_tris, &sc->surf, s[e].origin,
                                 s[e].direction, hit[e], true, true, overflow);
#endif
    }
    ShadowQuery q[LANES];
    bool alive[LANES];
    int shadow[LANES];
#ifdef LANES_SHADE
    // The camera hits shaded together (shade_lanes.h).
    ShadeBatch B;
    for (uint e = 0u; e < n; ++e) shade_batch_put(&B, (int)e, &s[e], 0u, hit[e]);
    lanes_shade(frame, sc, &B, (int)n);
#endif
    for (uint e = 0u; e < n; ++e) {
#ifdef LANES_SHADE
        alive[e] = shade_batch_get(&B, (int)e, &s[e], &q[e]);
#else
        alive[e] = shade_vertex(frame, 0u, sc, hit[e], &s[e], &q[e]);
#endif
        shadow[e] = q[e].valid ? -1 : 0;
        c->rays[e] += q[e].valid;
        if (q[e].valid) packet_take_ray(&P, &R, (int)e, q[e].origin, q[e].direction, q[e].tmax);
    }
    for (uint e = n; e < (uint)LANES; ++e) shadow[e] = 0;
    vint shadows = vload_lanes(0, shadow);
    if (lanes_any(shadows)) {
        packet_set_rays(&P, &R);
        W->shadow_rays += (uint)lanes_count(shadows);
        packet_walk(&P, shadows, true, nodes, sc->tris, &sc->surf, overflow);
        for (uint e = 0u; e < n; ++e) {
            if (!shadow[e]) continue;
            if (P.prim[e] < 0) {
                s[e].radiance += q[e].contribution;
            } else {
#ifdef HAS_THIN_WALLS
                // Blocked: perhaps only by thin walls, which the scalar test passes.
                s[e].radiance +=
                    shadow_pass_wide(nodes, sc->tris, instances, object_tris, &sc->surf, &q[e],
                                     overflow);
#endif
            }
        }
    }
    // The paths that go on wait for lanes; the others are done.
    W->queue_head = 0u;
    W->queue_end = 0u;
    for (uint e = 0u; e < n; ++e) {
        if (alive[e]) {
            uint k = W->queue_end++;
            if (k != e) s[k] = s[e];
            W->queued_chunk[k] = (uint)r;
            W->queued_entry[k] = e;
        } else {
            mega_path_done(W, frame, film, (uint)r, e, &s[e]);
        }
    }
    return true;
}

// The paths in flight, MEGA_SLOTS of them: each in a lane (its ray walking), ready (its next
// ray, or its light sample's segment, waiting for a lane: the queue `ready`), free (the stack
// `free_slot`), or with LANES_SHADE in the batch (its vertex waiting to be shaded with others).
typedef struct {
    PathState s[MEGA_SLOTS];
    uint bounce[MEGA_SLOTS], chunk[MEGA_SLOTS], entry[MEGA_SLOTS];
    // A path whose next ray is its vertex's light sample: the sample, and whether the path goes
    // on after it.
    ShadowQuery sample[MEGA_SLOTS];
    bool in_shadow[MEGA_SLOTS], goes_on[MEGA_SLOTS];
#ifdef LAST_RAY_EMITTERS
    // A path whose next ray is its last ray's segment to the emitter it meets: that hit.
    bool to_emitter[MEGA_SLOTS];
    DeviceHit emitter[MEGA_SLOTS];
    bool last_by_emitters;
#endif
    int ready[MEGA_SLOTS], free_slot[MEGA_SLOTS];
    uint ready_head, ready_count, free_count;
#ifdef LANES_SHADE
    ShadeBatch B;
    int batch_slot[LANES];
    int batch_n;  // vertices in the batch
#endif
} MegaSlots;

// Path k's next ray is ready.
inline void slot_ready(MegaSlots* S, int k) {
    S->ready[(S->ready_head + S->ready_count++) % MEGA_SLOTS] = k;
}

// Path k's next ray (alive), or its end (the last ray first tested against the emitters).
inline void slot_next(MegaSlots* S, MegaWork* W, const DeviceFrame* frame, const ShadeScene* sc,
                      global ulong4* film, int k, bool alive) {
#ifdef LAST_RAY_EMITTERS
    if (alive && S->last_by_emitters && S->bounce[k] == frame->max_bounces + 1u) {
        DeviceHit e = mega_nearest_emitter(frame, sc, S->s[k].origin, S->s[k].direction);
        if (e.prim != NO_HIT) {
            S->to_emitter[k] = true;
            S->emitter[k] = e;
        } else {
            alive = false;  // it meets no emitter: it would add nothing
        }
    }
#endif
    if (alive) {
        slot_ready(S, k);
    } else {
        mega_path_done(W, frame, film, S->chunk[k], S->entry[k], &S->s[k]);
        S->free_slot[S->free_count++] = k;
    }
}

// Path k's vertex shaded (alive: whether the path goes on): its light sample, else its next
// ray, is ready.
inline void slot_shaded(MegaSlots* S, MegaWork* W, const DeviceFrame* frame,
                        const ShadeScene* sc, global ulong4* film, int k, bool alive) {
    alive = alive && ++S->bounce[k] <= frame->max_bounces + 1u;
    if (S->sample[k].valid) {
        ++W->shadow_rays;
        ++W->chunk[S->chunk[k]].rays[S->entry[k]];
        S->in_shadow[k] = true;
        S->goes_on[k] = alive;
        slot_ready(S, k);
    } else {
        slot_next(S, W, frame, sc, film, k, alive);
    }
}

#ifdef LANES_SHADE
// The batch's vertices shaded together (shade_lanes.h), each path then as slot_shaded says.
inline void slots_shade_batch(MegaSlots* S, MegaWork* W, const DeviceFrame* frame,
                              const ShadeScene* sc, global ulong4* film) {
    lanes_shade(frame, sc, &S->B, S->batch_n);
    for (int e = 0; e < S->batch_n; ++e) {
        int k = S->batch_slot[e];
        slot_shaded(S, W, frame, sc, film, k, shade_batch_get(&S->B, e, &S->s[k], &S->sample[k]));
    }
    S->batch_n = 0;
}
#endif

// The lanes' loop: MEGA_SLOTS paths in flight, each in a lane (its ray walking), ready (its
// next ray, or its light sample's segment, waiting for a lane), free, or with LANES_SHADE in
// the batch (its vertex waiting to be shaded with others; shade_lanes.h). A path traces one
// ray at a time, its light sample before its next ray, so each path adds its light in the
// order of megakernel.cl's one-pixel kernel: the same image.
kernel void megakernel(MEGAKERNEL_PARAMS) {
    // The work item's square of pixels, LANES_TILE on a side.
    uint tiles_x = (frame.width + LANES_TILE - 1u) / LANES_TILE;
    MegaWork W;
    W.tile_x = (uint)get_global_id(0) % tiles_x * LANES_TILE;
    W.tile_y = (uint)get_global_id(0) / tiles_x * LANES_TILE;
    if (W.tile_y >= frame.height || frame.samples_in_wave == 0u) return;
    W.tile_w = min((uint)LANES_TILE, frame.width - W.tile_x);
    W.tile_h = min((uint)LANES_TILE, frame.height - W.tile_y);
    W.next_pixel = 0u;
    W.queue_head = W.queue_end = 0u;
    W.extension_rays = W.shadow_rays = W.nonfinite = 0u;
    W.halves = halves;
    W.state = state;
    W.rays = rays;
    for (int i = 0; i < MEGA_CHUNKS; ++i) {
        W.chunk[i].remaining = 0u;
        W.chunk[i].more = false;
    }
    ShadeScene sc = mega_shade_scene(environment, tris, instances, shading, uvs, tangents, colors,
                                     materials, tex_refs, textures, texels, env_texels,
                                     env_marginal, env_conditional, lights, light_cdf);
    volatile global uint* overflow = &counters[COUNT_OVERFLOW];
    LaneMemory M;
    lanes_init(&M);
#ifdef LANES_SMALL
    uint small_first[4], small_end[4];
    lanes_small_ranges(nodes, frame.triangles, small_first, small_end);
#endif
    LanesRays R;  // rays given to lanes, set in their fields together
    lanes_rays_init(&R);
    MegaSlots S;
#ifdef LAST_RAY_EMITTERS
    S.last_by_emitters = mega_last_ray_by_emitters(&frame);
#endif
    int lane_slot[LANES];  // the path of each lane's ray, -1: idle
    uint idle_lanes = (1u << LANES) - 1u;  // bit l: lane l idle
    S.ready_head = S.ready_count = 0u;
    S.free_count = MEGA_SLOTS;
#ifdef LANES_SHADE
    S.batch_n = 0;
#endif
    for (int k = 0; k < MEGA_SLOTS; ++k) {
        S.free_slot[k] = MEGA_SLOTS - 1 - k;
#ifdef LAST_RAY_EMITTERS
        S.to_emitter[k] = false;
#endif
    }
    for (int l = 0; l < LANES; ++l) lane_slot[l] = -1;
    for (;;) {
        // Idle lanes take ready rays, then new paths (starting chunks while the queue is
        // empty); lanes left idle with vertices waiting have the batch shaded at once.
        bool idle = false;
        for (uint bits = idle_lanes; bits != 0u; bits &= bits - 1u) {
            int l = (int)__builtin_ctz(bits);
            int k = -1;
            if (S.ready_count > 0u) {
                k = S.ready[S.ready_head];
                S.ready_head = (S.ready_head + 1u) % MEGA_SLOTS;
                --S.ready_count;
            } else if (S.free_count > 0u) {
                while (W.queue_head == W.queue_end &&
                       mega_chunk_start(&W, &frame, &camera, &sc, nodes, instances, object_tris,
                                        film, overflow)) {
                }
                if (W.queue_head < W.queue_end) {
                    uint q = W.queue_head++;
                    k = S.free_slot[--S.free_count];
                    S.s[k] = W.queued[q];
                    S.chunk[k] = W.queued_chunk[q];
                    S.entry[k] = W.queued_entry[q];
                    S.bounce[k] = 1u;
                    S.in_shadow[k] = false;
                }
            }
            if (k < 0) {
                idle = true;
                continue;
            }
            lane_slot[l] = k;
            idle_lanes &= ~(1u << l);
#ifdef LAST_RAY_EMITTERS
            if (S.to_emitter[k]) {
                lanes_take_ray(&M, &R, l, S.s[k].origin, S.s[k].direction, S.emitter[k].t, true);
                continue;
            }
#endif
            if (S.in_shadow[k]) {
                lanes_take_ray(&M, &R, l, S.sample[k].origin, S.sample[k].direction,
                               S.sample[k].tmax, true);
            } else {
                lanes_take_ray(&M, &R, l, S.s[k].origin, S.s[k].direction, INFINITY, false);
            }
        }
        if (R.taken != 0u) {
            lanes_set_rays(&M, &R);
            R.taken = 0u;
        }
#ifdef LANES_SHADE
        if (idle && S.batch_n > 0) {
            slots_shade_batch(&S, &W, &frame, &sc, film);
            continue;
        }
#endif
#ifdef LANES_SMALL
        vint done = lanes_walk_small(&M, nodes, tris, small_first, small_end, &sc.surf);
#else
        vint done = lanes_walk(&M, nodes, tris, &sc.surf, overflow);
#endif
        if (!lanes_any(done)) break;
        // The lanes done, in order (lowest first).
        for (uint bits = lanes_kmask(done); bits != 0u; bits &= bits - 1u) {
            int l = (int)__builtin_ctz(bits);
            int k = lane_slot[l];
            lane_slot[l] = -1;
            idle_lanes |= 1u << l;
#ifdef LAST_RAY_EMITTERS
            if (S.to_emitter[k]) {
                // The last ray's segment to its emitter walked: unblocked, the emitter is its
                // closest hit. The path ends.
                S.to_emitter[k] = false;
                ++W.extension_rays;
                ++W.chunk[S.chunk[k]].rays[S.entry[k]];
                if (M.prim[l] < 0) {
                    shade_vertex(&frame, S.bounce[k], &sc, S.emitter[k], &S.s[k], &S.sample[k]);
                }
                slot_next(&S, &W, &frame, &sc, film, k, false);
                continue;
            }
#endif
            if (S.in_shadow[k]) {
                // The vertex's light sample walked: its light is added (unless blocked, perhaps
                // only by thin walls, which the scalar test passes) before the path goes on.
                S.in_shadow[k] = false;
                if (M.prim[l] < 0) {
                    S.s[k].radiance += S.sample[k].contribution;
                } else {
#ifdef HAS_THIN_WALLS
                    S.s[k].radiance += shadow_pass_wide(nodes, tris, instances, object_tris,
                                                        &sc.surf, &S.sample[k], overflow);
#endif
                }
                slot_next(&S, &W, &frame, &sc, film, k, S.goes_on[k]);
                continue;
            }
            // The vertex the extension ray found: shaded at once, or with LANES_SHADE once the
            // batch is full.
            ++W.extension_rays;
            ++W.chunk[S.chunk[k]].rays[S.entry[k]];
#ifdef LANES_SHADE
            shade_batch_put(&S.B, S.batch_n, &S.s[k], S.bounce[k], lanes_hit(&M, l));
            S.batch_slot[S.batch_n++] = k;
            if (S.batch_n == LANES) slots_shade_batch(&S, &W, &frame, &sc, film);
#else
            slot_shaded(&S, &W, &frame, &sc, film, k,
                        shade_vertex(&frame, S.bounce[k], &sc, lanes_hit(&M, l), &S.s[k],
                                     &S.sample[k]));
#endif
        }
    }
    mega_count(counters, W.extension_rays, W.shadow_rays, W.nonfinite);
}
#endif  // MEGA_LANES
