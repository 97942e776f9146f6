# primary.s — primary-ray casting on one SPU, after Benthin et al. 2006, sections 4-5 and 8.
#
# The SPU takes 64x64 tiles from a shared counter, traces each tile as 64 packets of 8x8
# rays, and writes one 1 KiB result block per packet to the frame buffer; at the end it
# writes its statistics, says "end of frame" in its outbound mailbox and stops with 0x2000
# (host protocol: modules/frame.s; block layout: modules/output.s).
#
# The program is composed of the kernel modules in kernels/modules/, one job each. The
# order of the code modules is the program's layout: the frame driver falls into ray
# generation, which falls into traversal, and the hot blocks keep their even/odd pairing
# and instruction-fetch lines. The hot blocks are `.sched` blocks: written in logical order
# with virtual registers, laid out in even/odd dual-issue pairs by the assembler
# (docs/sched.md).
#
# Main-memory layouts (node: min.xyz, link | max.xyz, count<<2|axis; sibling pairs share a
# 64-byte line; triangle: Wald's projection record) and the kernel ABI come from
# loader::layout and loader::kernel_abi through layout.inc.

        .include "layout.inc"
        .include "modules/regs.inc"
        .include "modules/data.s"

        .include "modules/frame.s"          # start-up and the tile loop
        .include "modules/raygen.s"         # ray generation and packet setup
        .include "modules/traverse.s"       # traversal steps
        .include "modules/bvh_cache.s"      # BVH cache misses
        .include "modules/triangle.s"       # leaves: the triangle test
        .include "modules/tri_cache.s"      # triangle cache misses
        .include "modules/lru.s"            # the 4-way caches' sets
        .include "modules/sht.s"            # software hyperthreading
        .include "modules/output.s"         # shading and packet output
        .ifdef  SHADE
        .include "modules/shade.s"          # --shade: i-sets, shading caches, diffuse
        .include "modules/shadow.s"         # --shade shadows: shadow packets
        .ifdef  REFLECT
        .include "modules/reflect.s"        # --shade reflect: reflected rays
        .endif
        .endif
        .include "modules/frame_done.s"     # statistics and the end of the frame
