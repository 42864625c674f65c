// Exclusive prefix sum of `len` u32 values, in place, in three dispatches:
//   scan_blocks  one workgroup per block of 1024 values: the block's exclusive scan, its total
//                into sums[block]
//   scan_sums    one workgroup: the exclusive scan of the block totals, any count (chunks of
//                1024 with a carry); the grand total into sums[blocks]
//   scan_add     every value gets its block's offset; data[len] = the grand total
// After it, data[i] = Σ data[0..i] for i < len and data[len] = Σ data[0..len], so a flag array
// becomes "rank among the flagged" and "was flagged" is data[i + 1] != data[i]. Integer sums:
// the result does not depend on thread timing.

struct ScanInfo {
    len: u32,
    blocks: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> info: ScanInfo;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;

const WG: u32 = 256u;
const PER_THREAD: u32 = 4u;
const BLOCK: u32 = 1024u;

var<workgroup> partial: array<u32, 256>;
var<workgroup> chunk_total: u32;

// Each thread's exclusive prefix of `value` across the workgroup (Hillis–Steele in shared memory).
fn workgroup_exclusive(lid: u32, value: u32) -> u32 {
    partial[lid] = value;
    workgroupBarrier();
    for (var offset = 1u; offset < WG; offset = offset * 2u) {
        var add = 0u;
        if lid >= offset {
            add = partial[lid - offset];
        }
        workgroupBarrier();
        partial[lid] += add;
        workgroupBarrier();
    }
    return partial[lid] - value;
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let base = wid.x * BLOCK + lid * PER_THREAD;
    var own: array<u32, 4>;
    var total = 0u;
    for (var k = 0u; k < PER_THREAD; k++) {
        own[k] = total;
        if base + k < info.len {
            total += data[base + k];
        }
    }
    let prefix = workgroup_exclusive(lid, total);
    for (var k = 0u; k < PER_THREAD; k++) {
        if base + k < info.len {
            data[base + k] = prefix + own[k];
        }
    }
    if lid == WG - 1u {
        sums[wid.x] = prefix + total;
    }
}

@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_index) lid: u32) {
    var carry = 0u;
    let chunks = (info.blocks + BLOCK - 1u) / BLOCK;
    for (var c = 0u; c < chunks; c++) {
        let base = c * BLOCK + lid * PER_THREAD;
        var own: array<u32, 4>;
        var total = 0u;
        for (var k = 0u; k < PER_THREAD; k++) {
            own[k] = total;
            if base + k < info.blocks {
                total += sums[base + k];
            }
        }
        let prefix = workgroup_exclusive(lid, total);
        for (var k = 0u; k < PER_THREAD; k++) {
            if base + k < info.blocks {
                sums[base + k] = carry + prefix + own[k];
            }
        }
        if lid == WG - 1u {
            chunk_total = prefix + total;
        }
        workgroupBarrier();
        carry += chunk_total;
        workgroupBarrier();
    }
    if lid == 0u {
        sums[info.blocks] = carry;
    }
}

@compute @workgroup_size(256)
fn scan_add(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if i < info.len {
        data[i] += sums[i / BLOCK];
    }
    if i == 0u {
        data[info.len] = sums[info.blocks];
    }
}
