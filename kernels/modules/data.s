# data.s — the ray tracer's local store: the parameter and statistics buffers, the
# constants (k_*: shuffle patterns, masks, tolerances), the output double buffer, and
# `cache_area`, which the frame driver carves into the BVH and triangle caches and the
# packet contexts at start (each context: a packet's rays in structure-of-arrays form, its
# traversal stack and what software hyperthreading saves; see loader::kernel_abi::context).

# ---- local-store data
        .data
        .align 7
params:         .space 128
lockbuf:        .space 128
cullbuf:        .space 128      # the leaf's cull verdicts, by triangle & 7 (modules/triangle.s)
statbuf:        .space 128
vars:           .space 608
nodebuf:        .space 64

        .align 4
k_pat:          .long 0x00010203, 0x00010203, 0x00010203, 0x00010203
                .long 0x04050607, 0x04050607, 0x04050607, 0x04050607
                .long 0x08090a0b, 0x08090a0b, 0x08090a0b, 0x08090a0b
                .long 0x0c0d0e0f, 0x0c0d0e0f, 0x0c0d0e0f, 0x0c0d0e0f
k_tpat:         .long 0x80808080, 0x00010203, 0x80808080, 0x00010203  # lane k to lanes 1, 3
                .long 0x80808080, 0x04050607, 0x80808080, 0x04050607
                .long 0x80808080, 0x08090a0b, 0x80808080, 0x08090a0b
                .long 0x80808080, 0x0c0d0e0f, 0x80808080, 0x0c0d0e0f
k_lanege:       .long -1, -1, -1, -1        # lanes >= k, k = 0..3
                .long 0, -1, -1, -1
                .long 0, 0, -1, -1
                .long 0, 0, 0, -1
k_axoff:        .long 0, 256, 512, 0        # (k, u, v) array offsets for projection axis k
                .long 256, 512, 0, 0
                .long 512, 0, 256, 0
k_kuv:          .long 0x00010203, 0x04050607, 0x08090a0b, 0x0c0d0e0f   # origin in (k,u,v) order
                .long 0x04050607, 0x08090a0b, 0x00010203, 0x0c0d0e0f
                .long 0x08090a0b, 0x00010203, 0x04050607, 0x0c0d0e0f
k_m3:           .long 0, 0, 0, -1
k_idx:          .long 0, 1, 2, 3
k_inc0:         .long 1, 0, 0, 0
k_colf0:        .float 0.0, 1.0, 2.0, 3.0
k_colf1:        .float 4.0, 5.0, 6.0, 7.0
k_ccol:         .float 0.0, 7.0, 0.0, 7.0
k_crow:         .float 0.0, 0.0, 7.0, 7.0
k_plo:          .long 0x00010203, 0x10111213, 0x04050607, 0x14151617
k_phi:          .long 0x08090a0b, 0x18191a1b, 0x0c0d0e0f, 0x1c1d1e1f
k_pa:           .long 0x00010203, 0x04050607, 0x10111213, 0x14151617
k_pb:           .long 0x08090a0b, 0x0c0d0e0f, 0x18191a1b, 0x1c1d1e1f
k_entry:        .long 0x00010203, 0x10111213, 0x80808080, 0x80808080
k_root:         .long 0x0c0d0e0f, 0x1c1d1e1f, 0x80808080, 0x80808080   # (link, meta, 0, 0)
k_bg:           .long 0x000000ff, 0x000000ff, 0x000000ff, 0x000000ff
k_ident:        .long 0x00010203, 0x04050607, 0x08090a0b, 0x0c0d0e0f
k_swap:         .long 0x04050607, 0x00010203, 0x0c0d0e0f, 0x08090a0b
k_negodd:       .long 0, 0x80000000, 0, 0x80000000
k_oddmask:      .long 0, -1, 0, -1
k_evenmask:     .long -1, 0, -1, 0
k_child0:       .long -1, -1, 0, 0
k_child1:       .long 0, 0, -1, -1
k_word0:        .long -1, 0, 0, 0
k_word1:        .long 0, -1, 0, 0
k_pc0:          .long 0x00010203, 0x04050607, 0x10111213, 0x80808080   # state of child 0
k_pc1:          .long 0x08090a0b, 0x0c0d0e0f, 0x14151617, 0x80808080   # ... of child 1
k_ntol:         .long 0xb5800000, 0xb5800000, 0xb5800000, 0xb5800000   # -2^-20
k_onetol:       .long 0x3f800008, 0x3f800008, 0x3f800008, 0x3f800008   # 1 + 2^-20
k_eps20:        .long 0x35800000, 0x35800000, 0x35800000, 0x35800000   # 2^-20
k_eps:          .long 0x3f7fff00, 0xbf800080, 0x3f7fff00, 0xbf800080   # 1-2^-16, -(1+2^-16)
k_epslo:        .long 0x3f7fff00, 0x3f7fff00, 0x3f7fff00, 0x3f7fff00
k_epshi:        .long 0x3f800080, 0x3f800080, 0x3f800080, 0x3f800080
k_shade:        .long 0x03030380, 0x07070780, 0x0b0b0b80, 0x0f0f0f80   # byte 3 of each word x3
k_ff:           .long 0x000000ff, 0x000000ff, 0x000000ff, 0x000000ff
k_c255:         .long 255, 255, 255, 255
k_abs:          .long 0x7fffffff, 0x7fffffff, 0x7fffffff, 0x7fffffff
        .ifdef  EXT_MULTIHINT
pfpass:         .long leaf_probe, 0, 0, 0     # the next leaf's prefetch pass (triangle.s)
k_trav_to:      .long first_changed, leaf, .Ltrav_on, 0   # a step's ways (traverse.s)
numbuf:         .space 128      # the leaf's triangles' n_d - o.n, by triangle & 7 (triangle.s)
cullmask:       .long 0, 0, 0, 0  # the cull's culled triangles: bit 31 - j, its first + j
cullbase:       .long 0, 0, 0, 0  # the cull's first triangle (triangle.s)
k_grow0:        .float 0.0, 2.0, 4.0, 6.0     # the groups' first rows (triangle.s)
k_rep:          .long 0x03030303, 0x07070707, 0x0b0b0b0b, 0x0f0f0f0f   # each word's low byte x4
k_pc2:          .long 0x00010203, 0x04050607, 0x18191a1b, 0x80808080   # (a0, a1, b2, 0)
k_c7:           .float 7.0, 7.0, 7.0, 7.0     # the last column
k_ctol:         .long 0, 0x3b800000, 0x3b800000, 0x3b800000   # (0, 2^-8 x3): the edges' margin
# a triangle's verdict and range of groups to test (culled, first, last: byte offsets of
# groups of 16 rays) by the groups the cull keeps (bit 3 - g: group g), triangle.s
k_grange:       .long -1, 0, 0, 0
                .long 0, 192, 192, 0
                .long 0, 128, 128, 0
                .long 0, 128, 192, 0
                .long 0, 64, 64, 0
                .long 0, 64, 192, 0
                .long 0, 64, 128, 0
                .long 0, 64, 192, 0
                .long 0, 0, 0, 0
                .long 0, 0, 192, 0
                .long 0, 0, 128, 0
                .long 0, 0, 192, 0
                .long 0, 0, 64, 0
                .long 0, 0, 192, 0
                .long 0, 0, 128, 0
                .long 0, 0, 192, 0
gforms:         .space 8*48     # per packet context (by tag): its directions' (x, y, z)
                                # at column 0 row 0, per column, per row (raygen.s)
        .endif

        .align 7
outbuf:         .space 2048     # two packet result blocks, alternating
        .align 7
cache_area:                     # carved at start: BVH tags, BVH lines, triangle tags, lines,
                                # packet contexts
