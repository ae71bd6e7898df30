/* compact.cl — order-preserving compaction of the wavefront's child queue on the device, so the
 * host never reads the children back between bounces (src/render/queue_compact.h drives it).
 * Input: childValid[i] for the child slots i < n = *queueCount * childSlots (shade_hits writes
 * childSlots = CLRT_CHILD_SLOTS(pathMode) slots per parent path). Output: the valid children, in slot
 * order, at [0, total) of paths/rays, and total in *nextCount (the length of the next bounce's queue,
 * read there on the device), both cut at queueCapacity (the paths buffer's length):
 *   compact_scan_blocks: per block of CLRT_COMPACT_GROUP * CLRT_COMPACT_ITEMS slots, each slot's
 *                        exclusive prefix of valid slots within its block (compactTarget) and the
 *                        block's count (blockSums);
 *   compact_scan_sums:   one work-group: the exclusive prefix of the block counts, in place, and the
 *                        total (a loop over chunks of blocks: any queue length);
 *   compact_scatter:     valid slot i goes to blockSums[i / block] + compactTarget[i].
 * Integer prefix sums are exact, so the order (and every image) is the same on every device.
 * OpenCL C 1.2: local memory and barriers only, no subgroups, no atomics. Reads no scene element. */
#ifndef CLRT_COMPACT_CL
#define CLRT_COMPACT_CL

#include "../src/shared/device_types.h"
#include "../src/shared/kernel_params.h"

#define CLRT_COMPACT_BLOCK (CLRT_COMPACT_GROUP * CLRT_COMPACT_ITEMS)

/* Exclusive prefix sum of v over the work-group (Hillis-Steele in local memory); *total: the sum of
 * every item's v. Every work-item of the group must call it (barriers). */
inline int Scan_GroupExclusive(int v, __local int* tmp, int* total) {
    const int lid = (int)get_local_id(0);
    tmp[lid] = v;
    barrier(CLK_LOCAL_MEM_FENCE);
    for (int offset = 1; offset < CLRT_COMPACT_GROUP; offset <<= 1) {
        int add = lid >= offset ? tmp[lid - offset] : 0;
        barrier(CLK_LOCAL_MEM_FENCE);
        tmp[lid] += add;
        barrier(CLK_LOCAL_MEM_FENCE);
    }
    int inclusive = tmp[lid];
    *total = tmp[CLRT_COMPACT_GROUP - 1];
    barrier(CLK_LOCAL_MEM_FENCE); /* tmp is written again by the caller's next scan */
    return inclusive - v;
}

__kernel __attribute__((reqd_work_group_size(CLRT_COMPACT_GROUP, 1, 1)))
void compact_scan_blocks(CLRT_KERNEL_PARAMS(compact_scan_blocks)) {
    __local int tmp[CLRT_COMPACT_GROUP];
    const int n = *queueCount * childSlots;
    const int block = (int)get_group_id(0);
    if (block * CLRT_COMPACT_BLOCK >= n) return; /* the whole group: no barrier is left half-reached */
    const int first = block * CLRT_COMPACT_BLOCK + (int)get_local_id(0) * CLRT_COMPACT_ITEMS;
    int flags[CLRT_COMPACT_ITEMS];
    int sum = 0;
    for (int k = 0; k < CLRT_COMPACT_ITEMS; ++k) {
        flags[k] = (first + k < n && childValid[first + k] != 0) ? 1 : 0;
        sum += flags[k];
    }
    int total;
    int offset = Scan_GroupExclusive(sum, tmp, &total);
    for (int k = 0; k < CLRT_COMPACT_ITEMS; ++k) {
        if (first + k < n) compactTarget[first + k] = offset;
        offset += flags[k];
    }
    if (get_local_id(0) == 0) blockSums[block] = total;
}

/* Launched as one work-group of CLRT_COMPACT_GROUP items. */
__kernel __attribute__((reqd_work_group_size(CLRT_COMPACT_GROUP, 1, 1)))
void compact_scan_sums(CLRT_KERNEL_PARAMS(compact_scan_sums)) {
    __local int tmp[CLRT_COMPACT_GROUP];
    const int n = *queueCount * childSlots;
    const int blocks = (n + CLRT_COMPACT_BLOCK - 1) / CLRT_COMPACT_BLOCK;
    int carry = 0;
    for (int base = 0; base < blocks; base += CLRT_COMPACT_BLOCK) { /* uniform over the group */
        const int first = base + (int)get_local_id(0) * CLRT_COMPACT_ITEMS;
        int v[CLRT_COMPACT_ITEMS];
        int sum = 0;
        for (int k = 0; k < CLRT_COMPACT_ITEMS; ++k) {
            v[k] = first + k < blocks ? blockSums[first + k] : 0;
            sum += v[k];
        }
        int total;
        int offset = carry + Scan_GroupExclusive(sum, tmp, &total);
        for (int k = 0; k < CLRT_COMPACT_ITEMS; ++k) {
            if (first + k < blocks) blockSums[first + k] = offset;
            offset += v[k];
        }
        carry += total;
    }
    if (get_local_id(0) == 0) *nextCount = min(carry, queueCapacity);
}

__kernel void compact_scatter(CLRT_KERNEL_PARAMS(compact_scatter)) {
    const int i = (int)get_global_id(0);
    if (i >= *queueCount * childSlots || childValid[i] == 0) return;
    const int target = blockSums[i / CLRT_COMPACT_BLOCK] + compactTarget[i];
    if (target >= queueCapacity) return; /* a queue that outgrows the paths buffer keeps its first children */
    paths[target] = nextPaths[i];
    rays[target] = nextRays[i];
}

#endif /* CLRT_COMPACT_CL */
