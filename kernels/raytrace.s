# raytrace.s — primary-ray casting on one SPU, after Benthin et al. 2006, sections 4-5 and 8.
#
# Host protocol (loader::runtime): $3 = SPU index, $4 = effective address of the 128-byte
# parameter block (PARAM_* below). The SPU takes 64x64 tiles from a shared counter with an
# atomic getllar/putllc increment, traces each tile as 64 packets of 8x8 rays, and writes
# one 1 KiB block per packet to the frame buffer at FB + (tile*64 + packet)*1024:
#   +0 hit triangle index[64] (0xffffffff = miss), +256 distance t[64] (along the
#   unnormalised camera ray), +512 eye-light shade 0xGGGGGGff[64], +768 reserved (zero).
# Pixels within a packet are row-major (ray i = row*8 + col). When no tile is left it
# writes its statistics (STAT_*) to STATS + index*128, sends 1 to its outbound mailbox and
# stops with code 0x2000.
#
# Traversal (paper section 4.1, Wald/Boulos/Shirley 2007) works on sibling pairs: one step
# takes an inner node the packet enters and tests both of its children at once, each with
# the first active ray's slab test and the packet's interval-arithmetic (IA) frustum test.
# The two children's tests are independent, so they fill each other's latencies. The BVH
# cache keeps each pair axis-major (transposed when the line is filled on a miss):
#   +0  (min0.x, max0.x, min1.x, max1.x)   +16 the same for y   +32 for z
#   +48 (link0', meta0, link1', meta1)     link' = child-pair byte offset (inner) or
#                                          first triangle (leaf); meta = (count<<2|axis)<<4
# so a step needs no horizontal reductions: per axis, the planes are put in (near, far)
# order for the first ray (PERMk), and every slab test becomes "max over the axes of
# (entry, -exit)" with the exit negated in the odd lanes by the multipliers themselves.
# The multipliers carry a factor (1 -/+ 2^-16), and the offsets an absolute margin, that
# widen every box a little, so rounding can only make a box test say "hit", never drop a
# ray that reaches a triangle. The decision (descend to the near child and push the far
# one, take the one that is entered, or pop) is made with masks, without branches; only
# the third case (first ray misses a child the frustum does not rule out) branches, to
# find_first. A stack entry is a state: (link', meta, first active ray).
#
# A leaf fetches its missing triangles with back-to-back DMAs and one wait, culls each
# triangle against the packet's corner rays, and tests the active rays (from the first
# active ray's group of 16 on) four vectors per pass with Wald's projection test.
#
# The hot blocks (the step, the ray loop, ray generation, the triangle setup, find_first's
# loop, the packet setup and output) are laid out in even/odd dual-issue pairs with the
# aid in kernels/sched/, which holds their logical-order sources.
#
# Main-memory layouts come from loader::layout (node: min.xyz, link | max.xyz,
# count<<2|axis; sibling pairs share a 64-byte line; triangle: Wald's projection record).

        .include "layout.inc"

# ---- registers (never names starting with sp/lr/rp/fp: the assembler reads those as $1/$0/$127)
# frame constants
        .set ZERO, 2            # 0.0 / 0
        .set ONE, 3             # 1.0f
        .set BIG, 4             # 1e30f
        .set NBIG, 5            # -1e30f
        .set ORIG, 6            # camera origin (x, y, z, 0)
        .set PAT0, 7            # shufb patterns splatting word 0..3
        .set PAT1, 8
        .set PAT2, 9
        .set PAT3, 10
        .set OR1X, 11           # first ray: origin * RX1 plus a margin (see set_first)
        .set EANODES, 12
        .set EATRIS, 13
        .set BTAGS, 14          # BVH cache: tags (16 bytes per line), lines of 64 bytes
        .set BDATA, 15
        .set BDATA16, 16        # BDATA + 16, + 32, + 48 (lqx bases for the line's quads)
        .set BDATA32, 17
        .set BDATA48, 18
        .set BMASK64, 19        # (lines - 1) * 64
        .set TTAGS, 20          # triangle cache
        .set TDATA, 21
        .set TMASK, 22
# statistics (preferred-slot integers, or vectors summed at the end)
        .set S_TRIS, 23         # triangle tests after culling
        .set S_CULLED, 24
        .set OR1Y, 25
        .set S_TLOOK, 26
        .set OBX, 27            # the same for PB
        .set OBY, 28
        .set OBZ, 29
        .set S_STEPS, 30        # pair steps (two box tests each)
        .set M1V, 31            # sum of first-ray miss masks (two lanes per child)
        .set EEV, 32            # sum of early-exit masks (two lanes per child)
        .set OXS, 33            # origin x, y, z splats
        .set OYS, 34
        .set OZS, 35
        .set SWAP, 36           # shufb pattern swapping the words of each pair
        .set SIGNS, 37          # 0x80000000 in every lane
        .set NEGODD, 38         # 0x80000000 in lanes 1 and 3
        .set OR1Z, 39
        .set STKBASE, 40
        .set ROOTST, 41         # the root as a traversal state
        .set NEGTAB, 42         # negtab: per axis all-ones when the first ray points down it
# packet constants
        .set PAX, 43            # IA multipliers: (lo(1-e), -lo(1+e), lo(1-e), -lo(1+e)), lo = min 1/d
        .set PAY, 44
        .set PAZ, 45
        .set PBX, 46            # the same with hi = max 1/d
        .set PBY, 47
        .set PBZ, 48
        .set OAX, 49            # IA offsets: -origin * PA (PB) minus a margin, or -1e30 on
        .set OAY, 50            # axes where directions have both signs (no IA bound there)
        .set OAZ, 51
        .set F2, 52             # (0, -tmax, 0, -tmax): tmax = the packet's largest hit distance
# first-ray data (set_first)
        .set RX1, 53            # (r(1-e), -r(1+e), r(1-e), -r(1+e)), r = 1/d of the first ray
        .set RY1, 54
        .set RZ1, 55
        .set PERMX, 56          # identity or pair swap: planes in (near, far) order
        .set PERMY, 57
        .set PERMZ, 58
        .set FREE59, 59         # free (the ray loop uses it as a temporary)
        .set FT_ADDR, 60        # address of the first ray's t vector, and its splat pattern
        .set FT_PAT, 61
        .set FIRST, 62          # index of the first active ray (splat)
# traversal state
        .set CUR, 63            # (link', meta, first, 0) of the node being expanded
        .set STK, 64            # stack pointer: entries are states, 16 bytes
        .set FREE65, 65         # free (the ray loop uses it as a temporary)
# temporaries: $66..$127

# ---- cold per-frame values kept in local store (lqa/stqa vars+V_*)
        .set V_TILE, 0
        .set V_PKT, 16
        .set V_OUTSEL, 32       # which output buffer (0/1024)
        .set V_TX, 48
        .set V_TY, 64
        .set V_EAFB, 80
        .set V_EACNT, 96
        .set V_EASTATS, 112
        .set V_TILESX, 128
        .set V_NTILES, 144
        .set V_MYID, 160
        .set V_DIR00, 176
        .set V_DU, 192
        .set V_DV, 208
        .set V_BMISS, 224       # statistics of the rarer events
        .set V_TMISS, 240
        .set V_LEAVES, 256
        .set V_PACKETS, 272
        .set V_EMPTY, 288       # the scene has no triangle

# ---- local-store data
        .data
        .align 7
params:         .space 128
lockbuf:        .space 128
statbuf:        .space 128
vars:           .space 320
nodebuf:        .space 64
negtab:         .space 48
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

        .align 4
ray_dx:         .space 256      # structure of arrays, 16 vectors of 4 rays each, contiguous
ray_dy:         .space 256      # in this order (stores use offsets from ray_dx)
ray_dz:         .space 256
ray_rx:         .space 256
ray_ry:         .space 256
ray_rz:         .space 256
ray_t:          .space 256
ray_id:         .space 256
ray_nd:         .space 256      # cosine numerator: (n.d)/|n| of the hit
ray_invd:       .space 256      # 1/|d|
corners:        .space 48       # corner rays' x, y, z (rays 0, 7, 56, 63)
        .align 7
outbuf:         .space 2048     # two packet result blocks, alternating
        .space  16              # below the stack: what popping an empty stack reads
stack:          .space 2048     # traversal stack
        .align 7
cache_area:                     # carved at start: BVH tags, BVH lines, triangle tags, lines

# ---- code
        .text
        .global _start
_start:
        il      ZERO, 0
        stqa    $3, vars+V_MYID
        # fetch the parameter block
        ila     $66, params
        il      $67, 128
        il      $68, 0
        wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $4
        wrch    $MFC_Size, $67
        wrch    $MFC_TagID, $68
        il      $69, 0x40
        wrch    $MFC_Cmd, $69
        il      $69, 1
        wrch    $MFC_WrTagMask, $69
        il      $69, 2
        wrch    $MFC_WrTagUpdate, $69
        rdch    $69, $MFC_RdTagStat

        # constants
        ilhu    ONE, 0x3f80
        ilhu    BIG, 0x7149
        iohl    BIG, 0xf2ca
        ilhu    NBIG, 0xf149
        iohl    NBIG, 0xf2ca
        ila     $66, k_pat
        lqd     PAT0, 0($66)
        lqd     PAT1, 16($66)
        lqd     PAT2, 32($66)
        lqd     PAT3, 48($66)
        lqa     $75, k_m3
        lqa     SWAP, k_swap
        ilhu    SIGNS, 0x8000
        lqa     NEGODD, k_negodd
        ila     NEGTAB, negtab
        ila     STKBASE, stack

        # parameters
        ila     $66, params
        lqd     $67, PARAM_EA_NODES($66)      # quad 0: nodes, tris, fb, counter
        ori     EANODES, $67, 0
        rotqbyi EATRIS, $67, 4
        rotqbyi $68, $67, 8
        stqa    $68, vars+V_EAFB
        rotqbyi $68, $67, 12
        stqa    $68, vars+V_EACNT
        lqd     $67, PARAM_WIDTH($66)         # quad 1: width, height, tiles_x, num_tiles
        rotqbyi $68, $67, 8
        stqa    $68, vars+V_TILESX
        rotqbyi $68, $67, 12
        stqa    $68, vars+V_NTILES
        lqd     ORIG, PARAM_ORIGIN($66)
        lqd     $68, PARAM_DIR00($66)
        lqd     $69, PARAM_DU($66)
        lqd     $70, PARAM_DV($66)
        andc    ORIG, ORIG, $75
        andc    $68, $68, $75
        andc    $69, $69, $75
        andc    $70, $70, $75
        stqa    $68, vars+V_DIR00
        stqa    $69, vars+V_DU
        stqa    $70, vars+V_DV
        shufb   OXS, ORIG, ORIG, PAT0
        shufb   OYS, ORIG, ORIG, PAT1
        shufb   OZS, ORIG, ORIG, PAT2
        lqd     $67, PARAM_BVH_LOG2($66)      # quad 6: bvh log2, tri log2, stats EA
        rotqbyi $68, $67, 8
        stqa    $68, vars+V_EASTATS
        # carve the caches: lines = 1 << log2
        il      $69, 1
        shl     $70, $69, $67                 # BVH lines
        rotqbyi $71, $67, 4
        shl     $71, $69, $71                 # triangle lines
        ai      BMASK64, $70, -1
        shli    BMASK64, BMASK64, 6
        ai      TMASK, $71, -1
        ila     BTAGS, cache_area
        shli    $72, $70, 4
        a       BDATA, BTAGS, $72
        ai      BDATA16, BDATA, 16
        ai      BDATA32, BDATA, 32
        ai      BDATA48, BDATA, 48
        shli    $72, $70, 6
        a       TTAGS, BDATA, $72
        shli    $72, $71, 4
        a       TDATA, TTAGS, $72
        # invalidate every tag of both caches
        il      $72, -1
        ori     $73, BTAGS, 0
1:      stqd    $72, 0($73)
        ai      $73, $73, 16
        ai      $70, $70, -1
        brnz    $70, 1b
        ori     $73, TTAGS, 0
1:      stqd    $72, 0($73)
        ai      $73, $73, 16
        ai      $71, $71, -1
        brnz    $71, 1b
        # the reserved quarter of both output blocks stays zero
        ila     $73, outbuf+768
        il      $74, 16
1:      stqd    ZERO, 0($73)
        stqd    ZERO, 1024($73)
        ai      $73, $73, 16
        ai      $74, $74, -1
        brnz    $74, 1b

        # the root node as a traversal state (link', meta, 0, 0); an inner root whose link
        # is 0 marks the empty scene (see loader::layout)
        ila     $66, nodebuf
        il      $67, 32
        wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, EANODES
        wrch    $MFC_Size, $67
        wrch    $MFC_TagID, ZERO
        il      $67, 0x40
        wrch    $MFC_Cmd, $67
        il      $67, 1
        wrch    $MFC_WrTagMask, $67
        il      $67, 2
        wrch    $MFC_WrTagUpdate, $67
        rdch    $67, $MFC_RdTagStat
        lqd     $67, 0($66)
        lqd     $68, 16($66)
        lqa     $69, k_root
        shufb   $70, $67, $68, $69            # (link, meta, 0, 0)
        rotqbyi $71, $70, 4
        rotmi   $71, $71, -2                  # triangle count
        ceqi    $72, $71, 0                   # inner
        shli    $73, $70, 5                   # child-pair byte offset
        lqa     $74, k_word0
        and     $72, $72, $74                 # lane 0 only
        ceqi    $75, $70, 0                   # link 0 ...
        and     $75, $75, $72                 # ... of an inner root: empty
        stqa    $75, vars+V_EMPTY
        selb    ROOTST, $70, $73, $72
        lqa     $74, k_word1
        shli    $73, ROOTST, 4                # meta << 4: axis * 16 in bits 4-5
        selb    ROOTST, ROOTST, $73, $74

        # statistics
        il      S_STEPS, 0
        il      M1V, 0
        il      EEV, 0
        il      S_TRIS, 0
        il      S_CULLED, 0
        il      S_TLOOK, 0
        stqa    ZERO, vars+V_BMISS
        stqa    ZERO, vars+V_TMISS
        stqa    ZERO, vars+V_LEAVES
        stqa    ZERO, vars+V_PACKETS
        stqa    ZERO, vars+V_OUTSEL

# ---- take the next tile: atomic fetch-and-increment of the shared counter
next_tile:
        ila     $66, lockbuf
        lqa     $69, k_inc0
        lqa     $70, vars+V_EACNT
2:      wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $70
        il      $67, 0xd0                     # getllar
        wrch    $MFC_Cmd, $67
        rdch    $68, $MFC_RdAtomicStat
        lqd     $71, 0($66)
        a       $72, $71, $69
        stqd    $72, 0($66)
        wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $70
        il      $67, 0xb4                     # putllc
        wrch    $MFC_Cmd, $67
        rdch    $68, $MFC_RdAtomicStat
        andi    $68, $68, 1
        brnz    $68, 2b                       # reservation lost: retry
        lqa     $73, vars+V_NTILES
        clgt    $68, $73, $71
        brz     $68, frame_done
        stqa    $71, vars+V_TILE
        # tile coordinates: TY = TILE / TILESX, TX = TILE % TILESX (few tiles per row)
        lqa     $74, vars+V_TILESX
        il      $75, 0
        ori     $76, $71, 0
3:      clgt    $68, $74, $76
        brnz    $68, 4f
        sf      $76, $74, $76
        ai      $75, $75, 1
        br      3b
4:      stqa    $76, vars+V_TX
        stqa    $75, vars+V_TY
        stqa    ZERO, vars+V_PKT

packet_loop:
        # ---- ray generation: d = dir00 + (px0 + col)*du + (py0 + row)*dv
        lqa     $66, vars+V_PKT
        lqa     $67, vars+V_TX
        lqa     $68, vars+V_TY
        lqa     $73, vars+V_DIR00
        lqa     $74, vars+V_DU
        lqa     $75, vars+V_DV
        andi    $69, $66, 7
        rotmi   $70, $66, -3
        shli    $71, $67, 6
        shli    $72, $68, 6
        shli    $69, $69, 3
        shli    $70, $70, 3
        a       $69, $69, $71                 # px0
        a       $70, $70, $72                 # py0
        csflt   $69, $69, 0
        csflt   $70, $70, 0
        shufb   $69, $69, $69, PAT0
        shufb   $70, $70, $70, PAT0
        shufb   $77, $74, $74, PAT0           # du, dv splats
        shufb   $78, $74, $74, PAT1
        fma     $76, $69, $74, $73
        shufb   $79, $74, $74, PAT2
        shufb   $80, $75, $75, PAT0
        fma     $76, $70, $75, $76            # base direction (x, y, z, 0)
        shufb   $81, $75, $75, PAT1
        shufb   $82, $75, $75, PAT2
        lqa     $86, k_ccol
        lqa     $87, k_crow
        shufb   $83, $76, $76, PAT0           # base x, y, z splats
        shufb   $84, $76, $76, PAT1
        shufb   $85, $76, $76, PAT2
        lqa     $91, k_colf0
        lqa     $92, k_colf1
        # corner rays (0, 7, 56, 63) for the packet frustum
        fma     $93, $87, $80, $83
        fma     $94, $87, $81, $84
        fma     $95, $87, $82, $85
        ila     $88, ray_dx                   # vector pointer
        il      $89, 0                        # row (float)
        fma     $93, $86, $77, $93
        fma     $94, $86, $78, $94
        fma     $95, $86, $79, $95
        il      $90, 4                        # row pairs left
        il      $118, -1
        stqa    $93, corners
        stqa    $94, corners+16
        stqa    $95, corners+32

        # four vectors (two rows) per pass, scheduled into even/odd pairs
        .align  3
.Lrow:
        fa      $86, $89, ONE   # the second row
        hbrr    .Lrow_br, .Lrow
        fma     $93, $89, $80, $83   # row part
        lnop
        fma     $94, $89, $81, $84
        lnop
        fma     $95, $89, $82, $85
        lnop
        fa      $89, $89, ONE
        lnop
        ai      $90, $90, -1
        lnop
        fma     $66, $86, $80, $83
        lnop
        fma     $67, $86, $81, $84
        lnop
        fma     $68, $86, $82, $85
        lnop
        fma     $96, $91, $77, $93   # dx, dy, dz of columns 0-3
        lnop
        fma     $97, $91, $78, $94
        lnop
        fma     $98, $91, $79, $95
        lnop
        fma     $99, $92, $77, $93   # columns 4-7
        lnop
        fma     $100, $92, $78, $94
        lnop
        fma     $101, $92, $79, $95
        lnop
        fma     $69, $91, $77, $66
        frest   $102, $96
        fma     $70, $91, $78, $67
        frest   $103, $97
        fma     $71, $91, $79, $68
        frest   $104, $98
        fma     $72, $92, $77, $66
        frest   $105, $99
        fma     $73, $92, $78, $67
        frest   $106, $100
        fma     $74, $92, $79, $68
        frest   $107, $101
        fi      $102, $96, $102
        stqd    $96, 0($88)
        fi      $103, $97, $103
        stqd    $97, 256($88)
        fi      $104, $98, $104
        stqd    $98, 512($88)
        fi      $105, $99, $105
        stqd    $99, 16($88)
        fi      $106, $100, $106
        stqd    $100, 272($88)
        fi      $107, $101, $107
        stqd    $101, 528($88)
        fm      $114, $96, $96   # |d|^2
        stqd    $69, 32($88)
        fm      $115, $99, $99
        stqd    $70, 288($88)
        fm      $66, $69, $69
        stqd    $71, 544($88)
        fm      $67, $72, $72
        frest   $75, $69
        fnms    $108, $96, $102, ONE
        frest   $76, $70
        fnms    $109, $97, $103, ONE
        frest   $87, $71
        fma     $114, $97, $97, $114
        frest   $119, $72
        fi      $75, $69, $75
        frest   $120, $73
        fi      $76, $70, $76
        frest   $121, $74
        fi      $87, $71, $87
        stqd    $72, 48($88)
        fi      $119, $72, $119
        stqd    $73, 304($88)
        fi      $120, $73, $120
        stqd    $74, 560($88)
        fi      $121, $74, $121
        lnop
        fma     $115, $100, $100, $115
        lnop
        fma     $66, $70, $70, $66
        lnop
        fma     $67, $73, $73, $67
        lnop
        fnms    $110, $98, $104, ONE
        lnop
        fnms    $111, $99, $105, ONE
        lnop
        fnms    $112, $100, $106, ONE
        lnop
        fnms    $113, $101, $107, ONE
        lnop
        fnms    $122, $69, $75, ONE
        lnop
        fnms    $123, $70, $76, ONE
        lnop
        fnms    $124, $71, $87, ONE
        lnop
        fnms    $125, $72, $119, ONE
        lnop
        fnms    $126, $73, $120, ONE
        lnop
        fnms    $127, $74, $121, ONE
        lnop
        fma     $114, $98, $98, $114
        lnop
        fma     $115, $101, $101, $115
        lnop
        fma     $66, $71, $71, $66
        lnop
        fma     $67, $74, $74, $67
        lnop
        fma     $102, $108, $102, $102   # 1/d, one Newton step
        lnop
        fma     $103, $109, $103, $103
        lnop
        fma     $104, $110, $104, $104
        frsqest $116, $114
        fma     $105, $111, $105, $105
        frsqest $117, $115
        fma     $106, $112, $106, $106
        frsqest $68, $66
        fma     $107, $113, $107, $107
        frsqest $86, $67
        fma     $75, $122, $75, $75
        lnop
        fma     $76, $123, $76, $76
        lnop
        fma     $87, $124, $87, $87
        lnop
        fma     $119, $125, $119, $119
        lnop
        fma     $120, $126, $120, $120
        lnop
        fma     $121, $127, $121, $121
        lnop
        fi      $116, $114, $116   # 1/|d|, ~12 bits: enough for shading
        stqd    $102, 768($88)
        fi      $117, $115, $117
        stqd    $103, 1024($88)
        fi      $68, $66, $68
        stqd    $104, 1280($88)
        fi      $86, $67, $86
        stqd    $105, 784($88)
        fa      $89, $89, ONE
        stqd    $106, 1040($88)
        nop
        stqd    $107, 1296($88)
        nop
        stqd    $75, 800($88)
        nop
        stqd    $76, 1056($88)
        nop
        stqd    $87, 1312($88)
        nop
        stqd    $119, 816($88)
        nop
        stqd    $120, 1072($88)
        nop
        stqd    $121, 1328($88)
        nop
        stqd    $116, 2304($88)
        nop
        stqd    $117, 2320($88)
        nop
        stqd    $68, 2336($88)
        nop
        stqd    $86, 2352($88)
        nop
        stqd    BIG, 1536($88)
        nop
        stqd    BIG, 1552($88)
        nop
        stqd    BIG, 1568($88)
        nop
        stqd    BIG, 1584($88)
        nop
        stqd    $118, 1792($88)
        nop
        stqd    $118, 1808($88)
        nop
        stqd    $118, 1824($88)
        nop
        stqd    $118, 1840($88)
        nop
        stqd    ZERO, 2048($88)
        nop
        stqd    ZERO, 2064($88)
        nop
        stqd    ZERO, 2080($88)
        nop
        stqd    ZERO, 2096($88)
        ai      $88, $88, 64
        lnop
        nop
.Lrow_br:
        brnz    $90, .Lrow

        # ---- packet setup, scheduled into even/odd pairs: the frustum for the IA box tests
        # (per axis the range of 1/d over the corner rays, which bounds every ray's 1/d
        # where the sign does not change), its multipliers and offsets (see trav), and the
        # first ray's data (set_first) for ray 0; then traversal from the root's children.
        # A box test computes plane * PA + OA with OA = -origin * PA - |origin * PA| * 2^-20:
        # the margin covers the rounding of the product it replaces; OA = -1e30 where the
        # directions have both signs and give no bound.
        .align  3
.Lsetup:
        il      FIRST, 0
        lqa     $66, corners
        ila     $106, k_pat
        lqa     $67, corners+16
        andi    $101, FIRST, 3
        lqa     $68, corners+32
        rotmi   $100, FIRST, -2
        lqa     $69, k_eps
        shli    $101, $101, 4   # its lane * 16
        lqa     $70, k_abs
        ila     $102, ray_rx
        lqa     $71, k_eps20
        ori     STK, STKBASE, 0
        frest   $72, $66
        shli    $100, $100, 4   # its vector's byte offset
        frest   $73, $67
        nop
        frest   $74, $68
        nop
        lqx     $107, $106, $101
        fi      $72, $66, $72
        lqa     $75, k_oddmask
        fi      $73, $67, $73
        lqa     $111, k_ident
        fi      $74, $68, $74
        lnop
        ila     $106, k_tpat
        lnop
        a       $102, $102, $100
        lnop
        nop
        lqx     FT_PAT, $106, $101
        ila     $106, ray_t
        lqd     $103, 0($102)
        fnms    $76, $66, $72, ONE
        lqd     $104, 256($102)
        fnms    $77, $67, $73, ONE
        lqd     $105, 512($102)
        fnms    $78, $68, $74, ONE
        lnop
        a       FT_ADDR, $106, $100
        lnop
        and     F2, NBIG, $75
        lqa     $106, k_eps
        nop
        shufb   $103, $103, $103, $107   # 1/d splats
        fma     $79, $76, $72, $72
        shufb   $104, $104, $104, $107
        fma     $80, $77, $73, $73
        shufb   $105, $105, $105, $107
        fma     $81, $78, $74, $74
        lnop
        fcgt    $108, ZERO, $103   # points down the axis
        lnop
        fm      RX1, $103, $106
        lnop
        fm      RY1, $104, $106
        lnop
        fm      RZ1, $105, $106
        rotqbyi $82, $79, 8
        fcgt    $109, ZERO, $104
        rotqbyi $83, $80, 8
        fcgt    $110, ZERO, $105
        rotqbyi $84, $81, 8
        selb    PERMX, $111, SWAP, $108
        lnop
        fcgt    $85, $79, $82
        lnop
        fcgt    $86, $80, $83
        lnop
        fcgt    $87, $81, $84
        lnop
        selb    $88, $79, $82, $85
        lnop
        selb    $89, $82, $79, $85
        lnop
        selb    $90, $80, $83, $86
        rotqbyi $91, $88, 4
        selb    $92, $83, $80, $86
        rotqbyi $93, $89, 4
        selb    $94, $81, $84, $87
        rotqbyi $95, $90, 4
        selb    $96, $84, $81, $87
        rotqbyi $97, $92, 4
        fcgt    $98, $88, $91
        rotqbyi $99, $94, 4
        fcgt    $113, $93, $89
        rotqbyi $114, $96, 4
        fcgt    $115, $90, $95
        lnop
        fcgt    $116, $97, $92
        lnop
        fcgt    $117, $94, $99
        lnop
        fcgt    $118, $114, $96
        lnop
        selb    $119, $88, $91, $98
        lnop
        selb    $120, $89, $93, $113
        lnop
        selb    $121, $90, $95, $115
        lnop
        selb    $122, $92, $97, $116
        lnop
        selb    $123, $94, $99, $117
        lnop
        selb    $124, $96, $114, $118
        lnop
        fm      $125, $119, $69
        lnop
        fm      $126, $120, $69
        lnop
        fm      $127, $121, $69
        lnop
        fm      $66, $122, $69
        lnop
        fm      $67, $123, $69
        lnop
        fm      $68, $124, $69
        lnop
        fcgt    $75, ZERO, $119
        lnop
        fcgt    $72, ZERO, $120
        lnop
        fcgt    $76, ZERO, $121
        lnop
        fcgt    $73, ZERO, $122
        lnop
        fcgt    $77, ZERO, $123
        lnop
        fcgt    $74, ZERO, $124
        lnop
        andc    $78, $75, $72
        lnop
        andc    $79, $76, $73
        lnop
        andc    $82, $77, $74
        lnop
        andc    $43, $125, $78
        lnop
        andc    $46, $126, $78
        lnop
        andc    $44, $127, $79
        lnop
        andc    $47, $66, $79
        lnop
        andc    $45, $67, $82
        lnop
        andc    $48, $68, $82
        lnop
        fm      $85, $33, $43
        lnop
        fm      $86, $33, $46
        lnop
        fm      $80, $34, $44
        lnop
        fm      $83, $34, $47
        lnop
        fm      $87, $35, $45
        lnop
        fm      $84, $35, $48
        lnop
        and     $81, $85, $70
        lnop
        and     $91, $86, $70
        lnop
        and     $88, $80, $70
        lnop
        and     $98, $83, $70
        lnop
        and     $89, $87, $70
        lnop
        and     $113, $84, $70
        lnop
        fma     $93, $81, $71, $85
        lnop
        fma     $90, $91, $71, $86
        lnop
        fma     $95, $88, $71, $80
        lnop
        fma     $115, $98, $71, $83
        lnop
        fma     $92, $89, $71, $87
        lnop
        fma     $97, $113, $71, $84
        lnop
        and     $116, NBIG, $78
        lnop
        and     $94, NBIG, $79
        lnop
        and     $117, NBIG, $82
        lnop
        fs      $49, $116, $93
        lnop
        fs      $27, $116, $90
        lnop
        fs      $50, $94, $95
        lnop
        fs      $28, $94, $115
        lnop
        fs      $51, $117, $92
        lnop
        fs      $29, $117, $97
        lnop
        selb    PERMY, $111, SWAP, $109
        lnop
        selb    PERMZ, $111, SWAP, $110
        lnop
        fm      $103, OXS, RX1
        stqd    $108, 0(NEGTAB)   # near child is child 1 when negative
        fm      $104, OYS, RY1
        stqd    $109, 16(NEGTAB)
        fm      $105, OZS, RZ1
        stqd    $110, 32(NEGTAB)
        ori     CUR, ROOTST, 0
        lqa     $112, k_abs
        nop
        lqa     $111, k_eps20
        nop
        lqa     $99, vars+V_EMPTY
        and     $106, $103, $112
        lnop
        and     $107, $104, $112
        lnop
        and     $108, $105, $112
        lnop
        fma     OR1X, $106, $111, $103
        lnop
        fma     OR1Y, $107, $111, $104
        lnop
        fma     OR1Z, $108, $111, $105
        lnop
        nop
        brnz    $99, packet_done
        nop
        br      .Lnewcur


# ---- one traversal step: test both children of CUR (an inner node the packet enters)
# $68/$70/$71: the pair's x/y/z planes, $73: (link', meta) of both children, $76: near
# child's table offset, $77: the entry a pop takes, $112: first-ray miss mask
# (lanes child 0, 0, 1, 1), $118: the children's first active rays.
        .align  3                             # pairs: even pipe at 8k, odd pipe at 8k+4
trav:
        and     $66, CUR, BMASK64   # the pair's cache line
        hbrr    .Lloop_br, trav
        nop
        rotqbyi $67, CUR, 4   # meta << 4
        rotmi   $72, $66, -2   # its tag's offset
        lqx     $68, BDATA, $66   # x planes (min0, max0, min1, max1)
        nop
        lqx     $70, BDATA16, $66   # y
        nop
        lqx     $71, BDATA32, $66   # z
        andi    $69, $67, 0x30   # split axis * 16
        lqd     $74, 0(FT_ADDR)   # the first ray's t
        rotmi   $97, $67, -6   # triangle count: a leaf
        lqx     $73, BDATA48, $66   # (link', meta) of both children
        nop
        lqx     $75, BTAGS, $72
        nop
        lqx     $76, NEGTAB, $69   # all ones: child 1 is the near one
        nop
        lqd     $77, -16(STK)   # the entry a pop takes
        nop
        lqa     $78, k_pc0
        nop
        lqa     $79, k_pc1
        nop
        shufb   $95, CUR, CUR, PAT2   # this node's first active ray: changed?
        ceq     $115, $75, CUR   # the line holds this pair
        shufb   $80, $68, $68, PERMX   # planes in (near, far) order for the first ray
        nop
        shufb   $81, $70, $70, PERMY
        nop
        shufb   $82, $71, $71, PERMZ
        ceq     $95, $95, FIRST
        shufb   $83, $74, $74, FT_PAT   # (0, t, 0, t)
        fms     $84, $80, RX1, OR1X   # first ray: (entry, -exit) per child and axis
        lnop
        fms     $85, $81, RY1, OR1Y
        brz     $95, first_changed
        fms     $86, $82, RZ1, OR1Z
        brnz    $97, leaf
        xor     $83, $83, NEGODD   # (0, -t, 0, -t)
        lnop
        fma     $87, $80, PAX, OAX   # packet: both bounds, the smaller taken
        lnop
        fma     $88, $80, PBX, OBX
        lnop
        fma     $89, $81, PAY, OAY
        lnop
        fma     $90, $81, PBY, OBY
        lnop
        fma     $91, $82, PAZ, OAZ
        lnop
        fma     $92, $82, PBZ, OBZ
        lnop
        fcgt    $93, $84, $85
        lnop
        fcgt    $95, $86, $83
        lnop
        selb    $94, $85, $84, $93   # max(x, y)
        lnop
        selb    $96, $83, $86, $95   # max(z, t)
        lnop
        fcgt    $99, $87, $88
        lnop
        fcgt    $97, $94, $96
        lnop
        fcgt    $101, $89, $90
        lnop
        fcgt    $103, $91, $92
        lnop
        selb    $98, $96, $94, $97   # first ray: (entry, -exit) over the axes
        lnop
        selb    $100, $87, $88, $99
        lnop
        selb    $102, $89, $90, $101
        shufb   $111, $98, $98, SWAP
        selb    $104, $91, $92, $103
        lnop
        fcgt    $105, $100, $102
        lnop
        fcgt    $107, $104, F2
        lnop
        selb    $106, $102, $100, $105
        lnop
        selb    $108, F2, $104, $107
        lnop
        xor     $111, $111, SIGNS   # (exit, -entry)
        lnop
        fcgt    $109, $106, $108
        lnop
        fcgt    $112, $98, $111   # the first ray misses (lanes child 0, 0, 1, 1)
        lnop
        selb    $110, $108, $106, $109   # packet: (entry, -exit) over the axes
        lnop
        ai      S_STEPS, S_STEPS, 1
        shufb   $116, $112, $112, PAT0   # child 0 missed, every lane
        ceq     $93, STK, STKBASE
        shufb   $113, $110, $110, SWAP
        nop
        shufb   $117, $112, $112, PAT2   # child 1 missed
        or      $118, $116, $76
        lnop
        xor     $113, $113, SIGNS
        lnop
        andc    $118, $118, $117   # go to child 1
        lnop
        fcgt    $114, $110, $113   # the frustum misses
        lnop
        selb    $119, $78, $79, $118   # next state's pattern
        brz     $115, bvh_miss
        selb    $120, $79, $78, $118   # pushed state's pattern
        lnop
        a       $124, $116, $117
        shufb   $122, $73, FIRST, $119
        andc    $125, $112, $114   # undecided: the first ray misses, the frustum not
        shufb   $123, $73, FIRST, $120
        shli    $124, $124, 4   # -32, -16, 0: stack delta - 16
        lnop
        and     $127, $112, $114   # early exits
        gb      $126, $125
        and     $121, $116, $117   # neither: pop
        lnop
        a       M1V, M1V, $112
        lnop
        a       EEV, EEV, $127
        lnop
        and     $93, $93, $121   # popping an empty stack: the packet is done
        brnz    $126, slow   # the third case: the only one that branches
        selb    CUR, $122, $77, $121
        lnop
        nop
        stqd    $123, 0(STK)   # stored either way; kept when both children go
        nop
        brnz    $93, packet_done
        a       STK, STK, $124
        lnop
        ai      STK, STK, 16
        lnop
        nop
.Lloop_br:
        br      trav

# a new state from a pop or a changed first ray: the step's own checks sort it out
        .set    .Lnewcur, trav

first_changed:
        shufb   FIRST, CUR, CUR, PAT2
        brsl    $0, set_first
        br      trav

# ---- the third case: the first ray misses a child the frustum does not rule out. Find the
# first ray from FIRST on that enters it; none means the child is skipped.
slow:
        ori     $126, FIRST, 0                # the children's first active rays
        brz     $125, .Lslow1
        shufb   $80, $68, $68, PAT0           # child 0: min, max planes
        shufb   $81, $68, $68, PAT1
        shufb   $82, $70, $70, PAT0
        shufb   $83, $70, $70, PAT1
        shufb   $84, $71, $71, PAT0
        shufb   $85, $71, $71, PAT1
        brsl    $0, find_first
        ceqi    $98, $97, -1
        brnz    $98, .Lslow1
        lqa     $98, k_child0
        andc    $112, $112, $98
        shufb   $99, $97, $97, PAT0
        lqa     $98, k_word0
        selb    $126, $126, $99, $98
.Lslow1:
        rotqbyi $90, $125, 8
        brz     $90, .Lslow_done
        shufb   $80, $68, $68, PAT2           # child 1
        shufb   $81, $68, $68, PAT3
        shufb   $82, $70, $70, PAT2
        shufb   $83, $70, $70, PAT3
        shufb   $84, $71, $71, PAT2
        shufb   $85, $71, $71, PAT3
        brsl    $0, find_first
        ceqi    $98, $97, -1
        brnz    $98, .Lslow_done
        lqa     $98, k_child1
        andc    $112, $112, $98
        shufb   $99, $97, $97, PAT0
        lqa     $98, k_word1
        selb    $126, $126, $99, $98
.Lslow_done:
        # the step's decision again, with the children's own first rays
        shufb   $116, $112, $112, PAT0
        shufb   $117, $112, $112, PAT2
        lqa     $78, k_pc0
        lqa     $79, k_pc1
        or      $118, $116, $76
        andc    $118, $118, $117
        selb    $119, $78, $79, $118
        selb    $120, $79, $78, $118
        and     $121, $116, $117
        shufb   $122, $73, $126, $119
        shufb   $123, $73, $126, $120
        a       $124, $116, $117
        shli    $124, $124, 4
        ceq     $93, STK, STKBASE
        and     $93, $93, $121
        selb    CUR, $122, $77, $121
        stqd    $123, 0(STK)
        brnz    $93, packet_done
        a       STK, STK, $124
        ai      STK, STK, 16
        br      .Lnewcur

# find_first: the first ray from FIRST on whose slab intervals with the box ($80/$81 min/max
# x, $82/$83 y, $84/$85 z planes, splats) overlap within [0, t], widened by 1 -/+ 2^-16;
# its index in $97, or -1. Uses $80..$111, $113..$124, $127.
find_first:
        fs      $80, $80, OXS
        fs      $81, $81, OXS
        fs      $82, $82, OYS
        fs      $83, $83, OYS
        fs      $84, $84, OZS
        fs      $85, $85, OZS
        rotmi   $86, FIRST, -3
        shli    $86, $86, 5                   # byte offset of the even vector at or below FIRST's
        rotmi   $117, $86, -2                 # its first ray
        lqa     $90, k_idx
        a       $117, $117, $90               # the ray indices of its lanes
        ai      $89, FIRST, -1
        lqa     $113, k_epslo
        lqa     $114, k_epshi
        ila     $88, ray_rx
        # two vectors per pass (scheduled into even/odd pairs)
        .align  3
1:
        a       $90, $88, $86
        lnop
        cgt     $91, $117, $89
        lnop
        ai      $92, $117, 4
        lqd     $93, 0($90)
        ai      $86, $86, 32
        lqd     $94, 256($90)
        cgt     $95, $92, $89
        lqd     $96, 512($90)
        ai      $117, $117, 8
        lqd     $98, 16($90)
        ceqi    $104, $86, 256
        lqd     $99, 272($90)
        nop
        lqd     $100, 528($90)
        fm      $101, $80, $93
        lqd     $102, 768($90)
        fm      $105, $81, $93
        lqd     $106, 784($90)
        fm      $107, $82, $94
        lnop
        fm      $108, $83, $94
        lnop
        fm      $109, $84, $96
        lnop
        fm      $110, $85, $96
        lnop
        fm      $111, $80, $98
        lnop
        fm      $116, $81, $98
        lnop
        fm      $118, $82, $99
        lnop
        fm      $119, $83, $99
        lnop
        fm      $120, $84, $100
        lnop
        fm      $121, $85, $100
        lnop
        fcgt    $122, $101, $105
        lnop
        fcgt    $123, $107, $108
        lnop
        fcgt    $124, $109, $110
        lnop
        selb    $127, $101, $105, $122
        lnop
        selb    $87, $105, $101, $122
        lnop
        selb    $92, $107, $108, $123
        lnop
        selb    $93, $108, $107, $123
        lnop
        selb    $94, $109, $110, $124
        lnop
        selb    $96, $110, $109, $124
        lnop
        fcgt    $98, $127, $92
        lnop
        fcgt    $99, $94, ZERO
        lnop
        fcgt    $100, $87, $93
        lnop
        fcgt    $122, $96, $102
        lnop
        fcgt    $101, $111, $116
        lnop
        fcgt    $105, $118, $119
        lnop
        fcgt    $108, $120, $121
        lnop
        selb    $123, $92, $127, $98
        lnop
        selb    $107, ZERO, $94, $99
        lnop
        selb    $109, $87, $93, $100
        lnop
        selb    $124, $96, $102, $122
        lnop
        selb    $110, $111, $116, $101
        lnop
        selb    $98, $116, $111, $101
        lnop
        selb    $127, $118, $119, $105
        lnop
        selb    $92, $119, $118, $105
        lnop
        selb    $99, $120, $121, $108
        lnop
        selb    $94, $121, $120, $108
        lnop
        fcgt    $87, $123, $107
        lnop
        fcgt    $93, $109, $124
        lnop
        fcgt    $100, $110, $127
        lnop
        fcgt    $102, $99, ZERO
        lnop
        fcgt    $122, $98, $92
        lnop
        fcgt    $96, $94, $106
        lnop
        selb    $116, $107, $123, $87
        lnop
        selb    $111, $109, $124, $93
        lnop
        selb    $101, $127, $110, $100
        lnop
        selb    $119, ZERO, $99, $102
        lnop
        selb    $105, $98, $92, $122
        lnop
        selb    $118, $94, $106, $96
        lnop
        fm      $108, $116, $113
        lnop
        fm      $121, $111, $114
        lnop
        fcgt    $120, $101, $119
        lnop
        fcgt    $87, $105, $118
        lnop
        selb    $123, $119, $101, $120
        lnop
        selb    $107, $105, $118, $87
        lnop
        fm      $124, $123, $113
        lnop
        fm      $93, $107, $114
        lnop
        fcgt    $109, $108, $121
        lnop
        andc    $127, $91, $109
        lnop
        nop
        gb      $100, $127
        fcgt    $110, $124, $93
        lnop
        andc    $99, $95, $110
        lnop
        shli    $102, $100, 4
        lnop
        nop
        gb      $98, $99
        or      $103, $102, $98
        lnop
        nop
        brnz    $103, 2f
        nop
        brz     $104, 1b

        il      $97, -1
        bi      $0
2:      clz     $103, $103                    # 8 lanes: the first = clz - 24
        ai      $103, $103, -32               # (less the 8 rays $117 has moved on)
        a       $97, $117, $103
        bi      $0

# ---- BVH cache miss: fetch the pair, store it axis-major in its line, redo the lookup.
bvh_miss:
        lqa     $80, vars+V_BMISS
        ai      S_STEPS, S_STEPS, -1          # the step runs again
        ai      $80, $80, 1
        stqa    $80, vars+V_BMISS
        stqx    CUR, BTAGS, $72               # the line now holds this pair
        a       $80, CUR, EANODES             # the pair's effective address
        ila     $81, nodebuf
        il      $82, 64
        il      $83, 1
        il      $84, 0x40
        wrch    $MFC_LSA, $81
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $80
        wrch    $MFC_Size, $82
        wrch    $MFC_TagID, $83
        wrch    $MFC_Cmd, $84
        il      $83, 2
        wrch    $MFC_WrTagMask, $83
        wrch    $MFC_WrTagUpdate, $83
        rdch    $83, $MFC_RdTagStat
        lqd     $84, 0($81)                   # (min0, link0)
        lqd     $85, 16($81)                  # (max0, meta0)
        lqd     $86, 32($81)
        lqd     $87, 48($81)
        lqa     $88, k_plo
        lqa     $89, k_phi
        lqa     $90, k_pa
        lqa     $91, k_pb
        shufb   $92, $84, $85, $88            # (min0.x, max0.x, min0.y, max0.y)
        shufb   $93, $86, $87, $88
        shufb   $94, $84, $85, $89            # (min0.z, max0.z, link0, meta0)
        shufb   $95, $86, $87, $89
        shufb   $96, $92, $93, $90            # x planes of both children
        shufb   $97, $92, $93, $91            # y
        shufb   $98, $94, $95, $90            # z
        shufb   $99, $94, $95, $91            # (link0, meta0, link1, meta1)
        rotmi   $100, $99, -2
        ceqi    $100, $100, 0                 # lanes 1, 3: inner child
        shufb   $100, $100, $100, SWAP
        lqa     $101, k_evenmask
        and     $100, $100, $101
        shli    $101, $99, 5                  # link * 32: the child pair's byte offset
        selb    $99, $99, $101, $100
        lqa     $101, k_oddmask
        shli    $100, $99, 4                  # meta << 4: axis * 16 in bits 4-5
        selb    $99, $99, $100, $101
        a       $102, BDATA, $66
        stqd    $96, 0($102)
        stqd    $97, 16($102)
        stqd    $98, 32($102)
        stqd    $99, 48($102)
        br      trav

# ---- set_first: the first ray's data from FIRST (splat)
set_first:
        rotmi   $100, FIRST, -2
        shli    $100, $100, 4                 # its vector's byte offset
        andi    $101, FIRST, 3
        shli    $101, $101, 4                 # its lane * 16
        ila     $102, ray_rx
        a       $102, $102, $100
        lqd     $103, 0($102)
        lqd     $104, 256($102)
        lqd     $105, 512($102)
        ila     $106, k_pat
        lqx     $107, $106, $101
        ila     $106, k_tpat
        lqx     FT_PAT, $106, $101
        ila     $106, ray_t
        a       FT_ADDR, $106, $100
        shufb   $103, $103, $103, $107        # 1/d splats
        shufb   $104, $104, $104, $107
        shufb   $105, $105, $105, $107
        lqa     $106, k_eps
        fm      RX1, $103, $106
        fm      RY1, $104, $106
        fm      RZ1, $105, $106
        fcgt    $108, ZERO, $103              # points down the axis
        fcgt    $109, ZERO, $104
        fcgt    $110, ZERO, $105
        lqa     $111, k_ident
        selb    PERMX, $111, SWAP, $108
        selb    PERMY, $111, SWAP, $109
        selb    PERMZ, $111, SWAP, $110
        stqd    $108, 0(NEGTAB)               # near child is child 1 when negative
        stqd    $109, 16(NEGTAB)
        stqd    $110, 32(NEGTAB)
        # OR1 = origin * RX1 + |origin * RX1| * 2^-20: plane * RX1 - OR1 is the slab
        # distance less a margin that covers the rounding of the product it replaces
        lqa     $111, k_eps20
        lqa     $112, k_abs
        fm      $103, OXS, RX1
        fm      $104, OYS, RY1
        fm      $105, OZS, RZ1
        and     $106, $103, $112
        and     $107, $104, $112
        and     $108, $105, $112
        fma     OR1X, $106, $111, $103
        fma     OR1Y, $107, $111, $104
        fma     OR1Z, $108, $111, $105
        bi      $0

# ---- leaf: test the active rays against each triangle of the leaf
leaf:
        lqa     $80, vars+V_LEAVES
        ori     $66, CUR, 0                   # first triangle
        rotqbyi $67, CUR, 4
        ai      $80, $80, 1
        rotmi   $67, $67, -6                  # count (meta << 4 >> 2 ... see bvh_miss)
        stqa    $80, vars+V_LEAVES
        # bring every missing triangle of the leaf into the cache with one wait: the
        # DMAs queue back to back, so a leaf pays the memory latency once
        ori     $76, $66, 0
        ori     $77, $67, 0
        il      $78, 0                        # any miss
        il      $79, 64
        hbrr    .Lpf_br, .Lpf
.Lpf:   and     $80, $76, TMASK
        shli    $81, $80, 4
        lqx     $82, TTAGS, $81
        ceq     $83, $82, $76
        brz     $83, .Lpf_miss                # hits fall through
.Lpf_next:
        ai      $76, $76, 1
        ai      $77, $77, -1
.Lpf_br:
        brnz    $77, .Lpf
        brz     $78, tri_loop
        il      $86, 2
        wrch    $MFC_WrTagMask, $86
        wrch    $MFC_WrTagUpdate, $86
        rdch    $86, $MFC_RdTagStat
tri_loop:
        ai      S_TLOOK, S_TLOOK, 1
        and     $80, $66, TMASK
        shli    $81, $80, 4
        shli    $82, $80, 6
        lqx     $83, TTAGS, $81
        a       $84, TDATA, $82
        ceq     $85, $83, $66
        brz     $85, tri_miss                 # hits fall through
        # (scheduled into even/odd pairs: the record's splats, the corner-ray frustum cull
        # of the triangle, the first active group's offset)
        .align  3
.Ltri_hit:
        ila     $90, k_axoff
        lqd     $86, TRI_N_U($84)   # (n_u, n_v, n_d, k)
        ila     $97, ray_dx
        lqd     $87, TRI_B_NU($84)   # (b_nu, b_nv, b_d, -)
        rotmi   $119, FIRST, -4
        lqd     $88, TRI_C_NU($84)   # (c_nu, c_nv, c_d, -)
        nop
        shufb   $124, $66, $66, PAT0   # triangle index
        shli    $119, $119, 6   # byte offset of the first group
        rotqbyi $89, $86, 12   # k
        nop
        shufb   $68, $86, $86, PAT0   # n_u
        nop
        shufb   $69, $86, $86, PAT1   # n_v
        nop
        shufb   $93, $86, $86, PAT2   # n_d
        shli    $89, $89, 4
        shufb   $71, $87, $87, PAT0   # b_nu
        fm      $95, $68, $68
        shufb   $73, $87, $87, PAT2   # b_d
        nop
        shufb   $74, $88, $88, PAT0   # c_nu
        nop
        shufb   $120, $88, $88, PAT2   # c_d
        nop
        lqx     $91, $90, $89   # (k, u, v) array offsets
        ila     $90, k_kuv
        shufb   $72, $87, $87, PAT1   # b_nv
        nop
        shufb   $75, $88, $88, PAT1   # c_nv
        fma     $95, $69, $69, $95
        lqx     $92, $90, $89
        a       $125, $97, $91   # base of d_k
        rotqbyi $98, $91, 4
        rotmi   $100, $91, -4
        rotqbyi $99, $91, 8
        fa      $95, $95, ONE
        shufb   $92, ORIG, ORIG, $92   # origin in (k, u, v) order
        a       $126, $97, $98   # d_u
        lnop
        a       $127, $97, $99   # d_v
        lnop
        rotmi   $101, $98, -4
        lnop
        ila     $97, corners
        shufb   $94, $92, $92, PAT0   # o_k
        rotmi   $102, $99, -4
        shufb   $121, $92, $92, PAT1   # o_u
        nop
        lqx     $103, $97, $100   # corner d_k
        nop
        lqx     $104, $97, $101   # corner d_u
        fs      $70, $93, $94
        shufb   $122, $92, $92, PAT2   # o_v
        nop
        lqx     $105, $97, $102   # corner d_v
        nop
        frsqest $96, $95
        fma     $106, $68, $104, $103
        lnop
        fnms    $70, $68, $121, $70
        lnop
        fi      $123, $95, $96   # 1/|n|, n = (1, n_u, n_v) in (k, u, v)
        lnop
        fma     $106, $69, $105, $106   # den = n.d
        lnop
        fnms    $70, $69, $122, $70   # num = n_d - o_k - n_u o_u - n_v o_v
        lnop
        nop
        frest   $107, $106
        fi      $107, $106, $107
        lnop
        fnms    $108, $106, $107, ONE
        lnop
        fma     $107, $108, $107, $107
        lnop
        fm      $107, $70, $107   # t
        lnop
        fma     $108, $107, $104, $121   # hit u
        lnop
        fma     $109, $107, $105, $122   # hit v
        lnop
        fcgt    $113, $107, ZERO   # in front
        lnop
        fma     $110, $71, $108, $73
        lnop
        fma     $111, $74, $108, $120
        lnop
        fma     $110, $72, $109, $110   # beta
        lnop
        fma     $111, $75, $109, $111   # gamma
        lnop
        fcgt    $114, ZERO, $110
        lnop
        fa      $112, $110, $111
        lnop
        fcgt    $115, ZERO, $111
        lnop
        and     $114, $114, $113
        lnop
        and     $115, $115, $113
        lnop
        nop
        gb      $114, $114
        nop
        gb      $115, $115
        fcgt    $116, $112, ONE
        lnop
        and     $116, $116, $113
        lnop
        ceqi    $114, $114, 15   # every corner outside one edge
        gb      $113, $113
        ceqi    $115, $115, 15
        gb      $116, $116
        ceqi    $113, $113, 0   # every corner behind
        lnop
        ceqi    $116, $116, 15
        lnop
        or      $113, $113, $114
        lnop
        or      $115, $115, $116
        lnop
        or      $113, $113, $115
        lnop
        sf      S_CULLED, $113, S_CULLED   # +1 when culled
        lnop
        nop
        brnz    $113, tri_next
        ai      S_TRIS, S_TRIS, 1

        # the inside test admits barycentrics down to -2^-20 (and a sum up to 1 + 2^-20),
        # so a ray through the shared edge of two triangles hits one of them whatever
        # the truncating arithmetic makes of the edge; the nearer hit wins as usual
        lqa     $76, k_ntol
        lqa     $77, k_onetol
        # (scheduled into even/odd pairs from the 4-vector test: loads, den = n.d, t,
        # barycentrics, hit = t in (0, t_old) and inside, selb updates of t, id, n.d/|n|)
        .align  3
ray_loop:
        ila     $59, ray_t
        lqx     $65, $125, $119
        ila     $78, ray_id
        lqx     $79, $126, $119
        ila     $80, ray_nd
        lqx     $81, $127, $119
        a       $82, $59, $119
        lnop
        a       $83, $78, $119
        lnop
        a       $84, $80, $119
        lqd     $85, 0($82)
        ai      $119, $119, 16
        lqd     $86, 16($82)
        fma     $87, $68, $79, $65
        lqd     $88, 32($82)
        nop
        lqx     $89, $125, $119
        nop
        lqx     $90, $126, $119
        nop
        lqx     $91, $127, $119
        ai      $119, $119, 16
        lqd     $92, 48($82)
        nop
        lqd     $93, 0($83)
        fma     $87, $69, $81, $87
        lqx     $94, $125, $119
        nop
        lqx     $95, $126, $119
        fma     $96, $68, $90, $89
        lqx     $97, $127, $119
        ai      $119, $119, 16
        lqd     $98, 0($84)
        nop
        lqd     $99, 16($83)
        nop
        lqx     $100, $125, $119
        fm      $101, $87, $123
        lqx     $102, $126, $119
        fma     $103, $68, $95, $94
        lqx     $104, $127, $119
        fma     $96, $69, $91, $96
        frest   $105, $87
        ai      $119, $119, 16
        lqd     $106, 16($84)
        nop
        lqd     $107, 32($83)
        ceqi    $112, $119, 256
        lqd     $108, 32($84)
        fma     $109, $68, $102, $100
        lqd     $110, 48($83)
        fma     $103, $69, $97, $103
        lqd     $111, 48($84)
        fi      $105, $87, $105
        frest   $113, $96
        fm      $114, $96, $123
        lnop
        fma     $109, $69, $104, $109
        lnop
        fi      $113, $96, $113
        frest   $115, $103
        fm      $116, $103, $123
        lnop
        fnms    $117, $87, $105, ONE
        lnop
        fi      $115, $103, $115
        lnop
        fm      $118, $109, $123
        frest   $59, $109
        fnms    $78, $96, $113, ONE
        lnop
        fma     $117, $117, $105, $105
        lnop
        fi      $59, $109, $59
        lnop
        fnms    $80, $103, $115, ONE
        lnop
        fma     $78, $78, $113, $113
        lnop
        fm      $65, $70, $117
        lnop
        fnms    $89, $109, $59, ONE
        lnop
        fma     $80, $80, $115, $115
        lnop
        fm      $94, $70, $78
        lnop
        fma     $79, $65, $79, $121
        lnop
        fma     $81, $65, $81, $122
        lnop
        fma     $89, $89, $59, $59
        lnop
        fm      $100, $70, $80
        lnop
        fcgt    $87, $85, $65
        lnop
        fma     $90, $94, $90, $121
        lnop
        fma     $96, $71, $79, $73
        lnop
        fma     $105, $74, $79, $120
        lnop
        fm      $103, $70, $89
        lnop
        fma     $95, $100, $95, $121
        lnop
        fma     $91, $94, $91, $122
        lnop
        fma     $113, $71, $90, $73
        lnop
        fma     $117, $74, $90, $120
        lnop
        fma     $97, $100, $97, $122
        lnop
        fma     $102, $103, $102, $121
        lnop
        fma     $109, $71, $95, $73
        lnop
        fma     $115, $74, $95, $120
        lnop
        fma     $104, $103, $104, $122
        lnop
        fma     $96, $72, $81, $96
        lnop
        fma     $105, $75, $81, $105
        lnop
        fma     $78, $71, $102, $73
        lnop
        fma     $59, $74, $102, $120
        lnop
        fma     $113, $72, $91, $113
        lnop
        fma     $117, $75, $91, $117
        lnop
        fma     $109, $72, $97, $109
        lnop
        fma     $115, $75, $97, $115
        lnop
        fma     $78, $72, $104, $78
        lnop
        fma     $59, $75, $104, $59
        lnop
        fa      $80, $96, $105
        lnop
        fa      $79, $113, $117
        lnop
        fcgt    $89, $76, $96
        lnop
        fa      $90, $109, $115
        lnop
        fcgt    $95, $76, $105
        lnop
        fa      $81, $78, $59
        lnop
        fcgt    $102, $76, $113
        lnop
        fcgt    $91, $76, $117
        lnop
        fcgt    $97, $76, $109
        lnop
        fcgt    $104, $76, $115
        lnop
        fcgt    $96, $76, $78
        lnop
        fcgt    $105, $76, $59
        lnop
        fcgt    $113, $80, $77
        lnop
        fcgt    $117, $65, ZERO
        lnop
        or      $89, $89, $95
        lnop
        fcgt    $109, $79, $77
        lnop
        fcgt    $115, $86, $94
        lnop
        fcgt    $78, $94, ZERO
        lnop
        or      $102, $102, $91
        lnop
        fcgt    $59, $90, $77
        lnop
        fcgt    $80, $88, $100
        lnop
        fcgt    $95, $100, ZERO
        lnop
        or      $97, $97, $104
        lnop
        fcgt    $79, $81, $77
        lnop
        fcgt    $91, $92, $103
        lnop
        fcgt    $90, $103, ZERO
        lnop
        or      $96, $96, $105
        lnop
        and     $87, $87, $117
        lnop
        or      $89, $89, $113
        lnop
        and     $115, $115, $78
        lnop
        or      $102, $102, $109
        lnop
        and     $80, $80, $95
        lnop
        or      $97, $97, $59
        hbrr    .Lray_br, ray_loop
        and     $91, $91, $90
        lnop
        or      $96, $96, $79
        lnop
        andc    $104, $87, $89
        lnop
        andc    $81, $115, $102
        lnop
        andc    $105, $80, $97
        lnop
        andc    $117, $91, $96
        lnop
        selb    $85, $85, $65, $104
        lnop
        selb    $93, $93, $124, $104
        lnop
        selb    $98, $98, $101, $104
        stqd    $85, 0($82)
        selb    $86, $86, $94, $81
        stqd    $93, 0($83)
        selb    $99, $99, $124, $81
        stqd    $98, 0($84)
        selb    $106, $106, $114, $81
        stqd    $86, 16($82)
        selb    $88, $88, $100, $105
        stqd    $99, 16($83)
        selb    $107, $107, $124, $105
        stqd    $106, 16($84)
        selb    $108, $108, $116, $105
        stqd    $88, 32($82)
        selb    $92, $92, $103, $117
        stqd    $107, 32($83)
        selb    $110, $110, $124, $117
        stqd    $108, 32($84)
        selb    $111, $111, $118, $117
        stqd    $92, 48($82)
        nop
        stqd    $110, 48($83)
        nop
        stqd    $111, 48($84)
        nop
.Lray_br:
        brz     $112, ray_loop


tri_next:
        ai      $66, $66, 1
        ai      $67, $67, -1
        brnz    $67, tri_loop
        # the packet's largest t shrinks as rays hit: refresh the IA exit bound
        ila     $80, ray_t
        .irp    J, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15
        lqd     (\J+81), \J*16($80)
        .endr
        .irp    J, 0, 2, 4, 6, 8, 10, 12, 14
        fcgt    (\J+100), (\J+82), (\J+81)
        .endr
        .irp    J, 0, 2, 4, 6, 8, 10, 12, 14
        selb    (\J+81), (\J+81), (\J+82), (\J+100)
        .endr
        .irp    J, 0, 4, 8, 12
        fcgt    (\J+100), (\J+83), (\J+81)
        .endr
        .irp    J, 0, 4, 8, 12
        selb    (\J+81), (\J+81), (\J+83), (\J+100)
        .endr
        fcgt    $100, $85, $81
        fcgt    $101, $93, $89
        selb    $81, $81, $85, $100
        selb    $89, $89, $93, $101
        fcgt    $100, $89, $81
        selb    $81, $81, $89, $100
        rotqbyi $83, $81, 8
        fcgt    $84, $83, $81
        selb    $81, $81, $83, $84
        rotqbyi $83, $81, 4
        fcgt    $84, $83, $81
        selb    $81, $81, $83, $84            # the largest t, every lane
        lqa     $84, k_oddmask
        and     $81, $81, $84
        xor     F2, $81, NEGODD               # (0, -tmax, 0, -tmax)

# ---- pop: continue with the entry on top of the stack, or finish the packet
pop:
        ceq     $126, STK, STKBASE
        lqd     CUR, -16(STK)
        ai      STK, STK, -16
        brnz    $126, packet_done
        br      .Lnewcur

.Lpf_miss:
        stqx    $76, TTAGS, $81               # the line now holds this triangle
        shli    $84, $80, 6
        a       $84, $84, TDATA
        shli    $85, $76, 6
        a       $85, $85, EATRIS
        il      $86, 1
        il      $87, 0x40
        wrch    $MFC_LSA, $84
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $85
        wrch    $MFC_Size, $79
        wrch    $MFC_TagID, $86
        wrch    $MFC_Cmd, $87
        lqa     $88, vars+V_TMISS
        il      $78, 1
        ai      $88, $88, 1
        stqa    $88, vars+V_TMISS
        br      .Lpf_next

tri_miss:
        # triangle cache miss: fetch the 64-byte record, then test it
        lqa     $86, vars+V_TMISS
        ai      $86, $86, 1
        stqa    $86, vars+V_TMISS
        stqx    $66, TTAGS, $81
        shli    $85, $66, 6
        a       $85, $85, EATRIS
        wrch    $MFC_LSA, $84
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $85
        il      $86, 64
        wrch    $MFC_Size, $86
        il      $86, 1
        wrch    $MFC_TagID, $86
        il      $86, 0x40
        wrch    $MFC_Cmd, $86
        il      $86, 2
        wrch    $MFC_WrTagMask, $86
        wrch    $MFC_WrTagUpdate, $86
        rdch    $86, $MFC_RdTagStat
        br      .Ltri_hit

# ---- the packet is done: shade and send its results
        .align  3
packet_done:
        .ifdef  SHADE                         # shading (--shade simple): modules/shade.s
        ila     $68, ray_dx
        lqa     $69, vars+V_TILE
        lqa     $70, vars+V_PKT
        shli    $69, $69, 6
        a       $69, $69, $70
        brsl    $0, shade_packet
        .endif
        # (scheduled into even/odd pairs) wait until this buffer's previous transfer (tag
        # 2 + OUTSEL/1024) is done; per ray the hit, t and the shade |n.d / |n| * 1/|d||
        # * 256 clamped to 255, gray and opaque, background for misses; put the 1 KiB block
        # to FB + (tile*64 + packet)*1024
        nop
        lqa     $67, vars+V_PACKETS
        ai      $68, $67, 1
        lnop
        nop
        stqa    $68, vars+V_PACKETS
        il      $69, 1
        lqa     $66, vars+V_OUTSEL
        ila     $70, outbuf
        lnop
        rotmi   $71, $66, -10
        lnop
        a       $80, $70, $66
        lnop
        ai      $81, $71, 2
        lnop
        shl     $72, $69, $81
        lnop
        nop
        wrch    $MFC_WrTagMask, $72
        il      $73, 2
        lnop
        nop
        wrch    $MFC_WrTagUpdate, $73
        nop
        rdch    $74, $MFC_RdTagStat
        ila     $75, ray_dx
        lqd     $76, 0+2048($75)
        nop
        lqd     $77, 0+2304($75)
        nop
        lqd     $78, 16+2048($75)
        nop
        lqd     $79, 16+2304($75)
        nop
        lqd     $82, 32+2048($75)
        nop
        lqd     $83, 32+2304($75)
        nop
        lqd     $84, 48+2048($75)
        fm      $85, $76, $77
        lqd     $86, 48+2304($75)
        nop
        lqd     $87, 64+2048($75)
        fm      $88, $78, $79
        lqd     $89, 64+2304($75)
        nop
        lqd     $90, 80+2048($75)
        fm      $91, $82, $83
        lqd     $92, 80+2304($75)
        nop
        lqd     $94, 96+2048($75)
        fm      $95, $84, $86
        lqd     $96, 96+2304($75)
        nop
        lqd     $97, 112+2048($75)
        fm      $98, $87, $89
        lqd     $99, 112+2304($75)
        nop
        lqa     $100, k_abs
        fm      $101, $90, $92
        lqa     $102, k_c255
        nop
        lqa     $103, k_shade
        fm      $104, $94, $96
        lqd     $105, 0+1792($75)
        nop
        lqd     $106, 16+1792($75)
        fm      $107, $97, $99
        lqd     $108, 32+1792($75)
        and     $109, $85, $100
        lqd     $110, 48+1792($75)
        and     $111, $88, $100
        lqd     $112, 64+1792($75)
        and     $113, $91, $100
        lqd     $114, 80+1792($75)
        and     $115, $95, $100
        lqd     $116, 96+1792($75)
        and     $117, $98, $100
        lqd     $118, 112+1792($75)
        and     $119, $101, $100
        lqa     $120, k_bg
        and     $121, $104, $100
        lqd     $122, 0+1536($75)
        and     $123, $107, $100
        lqd     $124, 16+1536($75)
        cfltu   $125, $109, 8
        lqd     $126, 32+1536($75)
        cfltu   $127, $111, 8
        lqd     $67, 48+1536($75)
        cfltu   $68, $113, 8
        lqd     $70, 64+1536($75)
        cfltu   $71, $115, 8
        lqd     $69, 80+1536($75)
        cfltu   $72, $117, 8
        lqd     $73, 96+1536($75)
        cfltu   $74, $119, 8
        lqd     $77, 112+1536($75)
        cfltu   $76, $121, 8
        stqd    $105, 0($80)
        cfltu   $78, $123, 8
        stqd    $122, 256($80)
        clgt    $79, $125, $102
        stqd    $106, 16($80)
        clgt    $83, $127, $102
        stqd    $124, 272($80)
        clgt    $82, $68, $102
        stqd    $108, 32($80)
        clgt    $84, $71, $102
        stqd    $126, 288($80)
        clgt    $86, $72, $102
        stqd    $110, 48($80)
        clgt    $89, $74, $102
        stqd    $67, 304($80)
        clgt    $87, $76, $102
        stqd    $112, 64($80)
        clgt    $92, $78, $102
        stqd    $70, 320($80)
        selb    $90, $125, $102, $79
        stqd    $114, 80($80)
        selb    $94, $127, $102, $83
        stqd    $69, 336($80)
        selb    $96, $68, $102, $82
        shufb   $99, $90, $90, $103
        selb    $97, $71, $102, $84
        shufb   $85, $94, $94, $103
        selb    $88, $72, $102, $86
        shufb   $91, $96, $96, $103
        selb    $95, $74, $102, $89
        shufb   $98, $97, $97, $103
        selb    $101, $76, $102, $87
        shufb   $104, $88, $88, $103
        selb    $107, $78, $102, $92
        shufb   $109, $95, $95, $103
        ceqi    $111, $105, -1
        shufb   $113, $101, $101, $103
        ceqi    $115, $106, -1
        shufb   $117, $107, $107, $103
        ceqi    $119, $108, -1
        stqd    $116, 96($80)
        ceqi    $121, $110, -1
        stqd    $73, 352($80)
        ceqi    $123, $112, -1
        stqd    $118, 112($80)
        ceqi    $122, $114, -1
        stqd    $77, 368($80)
        ceqi    $124, $116, -1
        lnop
        ceqi    $126, $118, -1
        lnop
        selb    $67, $99, $120, $111
        lnop
        selb    $70, $85, $120, $115
        lnop
        selb    $125, $91, $120, $119
        stqd    $67, 512($80)
        selb    $79, $98, $120, $121
        stqd    $70, 528($80)
        selb    $127, $104, $120, $123
        stqd    $125, 544($80)
        selb    $83, $109, $120, $122
        stqd    $79, 560($80)
        selb    $69, $113, $120, $124
        stqd    $127, 576($80)
        selb    $82, $117, $120, $126
        stqd    $83, 592($80)
        nop
        stqd    $69, 608($80)
        nop
        stqd    $82, 624($80)
        nop
        lnop
        il      $68, 1024
        lqd     $90, 128+2048($75)
        il      $71, 0x20
        lqd     $84, 128+2304($75)
        nop
        lqd     $94, 144+2048($75)
        nop
        lqd     $86, 144+2304($75)
        nop
        lqd     $72, 160+2048($75)
        nop
        lqd     $96, 160+2304($75)
        nop
        lqd     $89, 176+2048($75)
        fm      $74, $90, $84
        lqd     $97, 176+2304($75)
        nop
        lqd     $87, 192+2048($75)
        fm      $76, $94, $86
        lqd     $88, 192+2304($75)
        nop
        lqd     $92, 208+2048($75)
        fm      $78, $72, $96
        lqd     $95, 208+2304($75)
        nop
        lqd     $105, 224+2048($75)
        fm      $101, $89, $97
        lqd     $106, 224+2304($75)
        and     $107, $74, $100
        lqd     $108, 240+2048($75)
        fm      $110, $87, $88
        lqd     $73, 240+2304($75)
        and     $112, $76, $100
        lqa     $114, vars+V_TILE
        fm      $77, $92, $95
        lqd     $116, 128+1792($75)
        and     $118, $78, $100
        lqd     $111, 144+1792($75)
        fm      $99, $105, $106
        lqd     $115, 160+1792($75)
        and     $85, $101, $100
        lqd     $119, 176+1792($75)
        fm      $91, $108, $73
        lqd     $67, 192+1792($75)
        and     $121, $110, $100
        lqd     $98, 208+1792($75)
        and     $70, $77, $100
        lqd     $104, 224+1792($75)
        cfltu   $123, $107, 8
        lqd     $125, 240+1792($75)
        and     $122, $99, $100
        lqa     $93, vars+V_PKT
        cfltu   $109, $112, 8
        lqd     $79, 128+1536($75)
        and     $124, $91, $100
        lqd     $113, 144+1536($75)
        cfltu   $127, $118, 8
        lqd     $126, 160+1536($75)
        cfltu   $117, $85, 8
        lqd     $83, 176+1536($75)
        cfltu   $69, $121, 8
        lqd     $82, 192+1536($75)
        cfltu   $90, $70, 8
        lqd     $84, 208+1536($75)
        cfltu   $94, $122, 8
        lqd     $86, 224+1536($75)
        cfltu   $96, $124, 8
        lqd     $72, 240+1536($75)
        clgt    $89, $123, $102
        lqa     $97, vars+V_EAFB
        clgt    $74, $109, $102
        stqd    $116, 128($80)
        clgt    $88, $127, $102
        stqd    $79, 384($80)
        clgt    $87, $117, $102
        stqd    $111, 144($80)
        clgt    $76, $69, $102
        stqd    $113, 400($80)
        clgt    $92, $90, $102
        stqd    $115, 160($80)
        clgt    $95, $94, $102
        stqd    $126, 416($80)
        clgt    $78, $96, $102
        stqd    $119, 176($80)
        selb    $105, $123, $102, $89
        stqd    $83, 432($80)
        selb    $106, $109, $102, $74
        stqd    $67, 192($80)
        selb    $101, $127, $102, $88
        shufb   $73, $105, $105, $103
        selb    $108, $117, $102, $87
        shufb   $110, $106, $106, $103
        selb    $77, $69, $102, $76
        shufb   $107, $101, $101, $103
        selb    $99, $90, $102, $92
        shufb   $112, $108, $108, $103
        selb    $91, $94, $102, $95
        shufb   $100, $77, $77, $103
        selb    $118, $96, $102, $78
        shufb   $85, $99, $99, $103
        shli    $121, $114, 6
        shufb   $70, $91, $91, $103
        ceqi    $122, $116, -1
        shufb   $124, $118, $118, $103
        ceqi    $75, $111, -1
        stqd    $82, 448($80)
        ceqi    $79, $115, -1
        stqd    $98, 208($80)
        ceqi    $113, $119, -1
        stqd    $84, 464($80)
        ceqi    $126, $67, -1
        stqd    $104, 224($80)
        ceqi    $89, $98, -1
        stqd    $86, 480($80)
        ceqi    $123, $104, -1
        stqd    $125, 240($80)
        ceqi    $83, $125, -1
        stqd    $72, 496($80)
        selb    $74, $73, $120, $122
        lnop
        selb    $109, $110, $120, $75
        lnop
        selb    $127, $107, $120, $79
        stqd    $74, 640($80)
        selb    $88, $112, $120, $113
        stqd    $109, 656($80)
        selb    $105, $100, $120, $126
        stqd    $127, 672($80)
        selb    $117, $85, $120, $89
        stqd    $88, 688($80)
        selb    $87, $70, $120, $123
        stqd    $105, 704($80)
        selb    $106, $124, $120, $83
        stqd    $117, 720($80)
        a       $69, $121, $93
        stqd    $87, 736($80)
        nop
        stqd    $106, 752($80)
        shli    $76, $69, 10
        lnop
        a       $101, $76, $97
        lnop
        nop
        wrch    $MFC_LSA, $80
        nop
        wrch    $MFC_EAH, ZERO
        nop
        wrch    $MFC_EAL, $101
        nop
        wrch    $MFC_Size, $68
        nop
        wrch    $MFC_TagID, $81
        nop
        wrch    $MFC_Cmd, $71
        xor     $92, $66, $68
        lnop
        nop
        stqa    $92, vars+V_OUTSEL
        ai      $90, $93, 1
        lnop
        nop
        stqa    $90, vars+V_PKT
        ceqi    $108, $90, 64
        lnop
        nop
        brz     $108, packet_loop
        nop
        br      next_tile


# ---- no tiles left: statistics, end-of-frame message, stop
frame_done:
        .ifdef  SHADE
        il      $80, 12 | 0xc0                # tags 2, 3 and the colours' 6, 7
        .else
        il      $80, 12                       # tags 2 and 3: the last results
        .endif
        wrch    $MFC_WrTagMask, $80
        il      $80, 2
        wrch    $MFC_WrTagUpdate, $80
        rdch    $80, $MFC_RdTagStat
        # the mask sums count -1 twice per child box: sum the lanes, halve
        .irp    V, M1V, EEV
        rotqbyi $81, \V, 8
        a       \V, \V, $81
        rotqbyi $81, \V, 4
        a       \V, \V, $81
        rotmai  \V, \V, -1
        .endr
        shli    $82, S_STEPS, 1               # box tests: two per pair step
        ila     $80, statbuf
        lqa     $81, k_entry
        lqa     $84, vars+V_PACKETS
        shufb   $83, $84, $82, $81
        stqd    $83, STAT_PACKETS($80)        # (packets, box tests, -, -)
        shufb   $83, M1V, EEV, $81
        stqd    $83, STAT_M1SUM($80)
        shufb   $83, S_TRIS, S_CULLED, $81
        stqd    $83, STAT_TRIS($80)
        lqa     $84, vars+V_BMISS
        lqa     $85, vars+V_LEAVES
        shufb   $83, $84, $85, $81
        stqd    $83, STAT_BMISS($80)
        lqa     $85, vars+V_TMISS
        shufb   $83, S_TLOOK, $85, $81
        stqd    $83, STAT_TLOOK($80)
        shufb   $83, S_STEPS, ZERO, $81
        stqd    $83, STAT_BLOOK($80)          # (BVH lookups = pair steps, -)
        lqa     $84, vars+V_MYID
        lqa     $85, vars+V_EASTATS
        shli    $83, $84, 7
        a       $83, $83, $85
        il      $84, 128
        il      $85, 4
        il      $86, 0x20
        wrch    $MFC_LSA, $80
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $83
        wrch    $MFC_Size, $84
        wrch    $MFC_TagID, $85
        wrch    $MFC_Cmd, $86
        il      $84, 16
        wrch    $MFC_WrTagMask, $84
        il      $84, 2
        wrch    $MFC_WrTagUpdate, $84
        rdch    $84, $MFC_RdTagStat
        il      $84, 1
        wrch    $SPU_WrOutMbox, $84
        stop    0x2000

        .ifdef  SHADE
        .include "modules/shade.s"
        .endif
