// bin_tiles.glsl: a 16x16 work group's pixels added to the compute path's material bins
// (render/compute_path.py `bins`) with one global atomic per material the tile holds, not one a
// pixel (~2 M a 1080p frame on a few dozen counters, which queue): a subgroup adds each
// material it holds once to the tile's slot in shared memory, then one invocation a slot adds
// the tile's total. A tile holding more than TILE_SLOTS materials adds the rest per subgroup.
// Used by classify.comp (counting, then scattering into the pixel list) and by raster.comp's
// resolve (counting as it writes the visibility image). Needs generated.glsl (bins) and the
// subgroup ballot, vote and shuffle extensions. Call tile_bins_begin(), then tile_bins_add()
// from every invocation (barriers: uniform control flow, no early return), then
// tile_bins_commit(); the counter is TILE_COUNTER's component of bins[m] (x: counts; z: the
// scatter's cursor, whose commit returns each slot's start in tile_base).
#ifndef BIN_TILES_GLSL
#define BIN_TILES_GLSL

#define TILE_SLOTS 16u
#define NO_MATERIAL 0xFFFFFFFFu
shared uint tile_material[TILE_SLOTS];  // filled in order, never changed once set
shared uint tile_count[TILE_SLOTS];
shared uint tile_base[TILE_SLOTS];      // after commit: the slot's start at the counter

void tile_bins_begin() {
    uint t = gl_LocalInvocationIndex;
    if (t < TILE_SLOTS) {
        tile_material[t] = NO_MATERIAL;
        tile_count[t] = 0u;
    }
    memoryBarrierShared();
    barrier();
}

// The tile's slot of material m (taken if new), or TILE_SLOTS when the tile has no room.
uint tile_slot(uint m) {
    for (uint i = 0u; i < TILE_SLOTS; ++i) {
        uint held = atomicCompSwap(tile_material[i], NO_MATERIAL, m);
        if (held == NO_MATERIAL || held == m) return i;
    }
    return TILE_SLOTS;
}

// This invocation's pixel (of `material` where `covered`) added; `slot` its tile slot
// (TILE_SLOTS: none, `offset` is then its place at the counter itself), `offset` its place
// in the slot.
void tile_bins_add(bool covered, uint material, out uint slot, out uint offset) {
    slot = TILE_SLOTS;
    offset = 0u;
    bool pending = covered;
    // Waterfall over the materials present in this subgroup: at most one round per lane
    // (each retires the first pending lane's material); the bound keeps a mistake here from
    // ever hanging a GPU.
    for (uint round = 0u; round < gl_SubgroupSize && subgroupAny(pending); ++round) {
        // The material of the first lane still pending (not of the first active lane: that
        // one may be done, and then no lane would match).
        uint m = subgroupShuffle(material, subgroupBallotFindLSB(subgroupBallot(pending)));
        bool mine = pending && material == m;
        uvec4 ballot = subgroupBallot(mine);
        if (mine) {
            uint n = subgroupBallotBitCount(ballot);
            uint leader = subgroupBallotFindLSB(ballot);
            uint got_slot = 0u, base = 0u;
            if (gl_SubgroupInvocationID == leader) {
                got_slot = tile_slot(m);
                base = got_slot < TILE_SLOTS ? atomicAdd(tile_count[got_slot], n)
                                             : atomicAdd(bins[m].TILE_COUNTER, n);
            }
            slot = subgroupShuffle(got_slot, leader);
            offset = subgroupShuffle(base, leader) + subgroupBallotExclusiveBitCount(ballot);
            pending = false;
        }
    }
    memoryBarrierShared();
    barrier();
}

// One global atomic per slot the tile filled; each slot's start in tile_base after it.
void tile_bins_commit() {
    uint t = gl_LocalInvocationIndex;
    if (t < TILE_SLOTS && tile_material[t] != NO_MATERIAL) {
        tile_base[t] = atomicAdd(bins[tile_material[t]].TILE_COUNTER, tile_count[t]);
    }
    memoryBarrierShared();
    barrier();
}

#endif
