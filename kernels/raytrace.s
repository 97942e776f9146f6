# raytrace.s — primary-ray casting on one SPU, after Benthin et al. 2006, sections 4-5 and 8.
#
# Host protocol (loader::runtime): $3 = SPU index, $4 = effective address of the 128-byte
# parameter block (PARAM_* below). The SPU takes 64x64 tiles from a shared counter with an
# atomic getllar/putllc increment, traces each tile as 64 packets of 8x8 rays, and writes
# one 1 KiB block per packet to the frame buffer at FB + (tile*64 + packet)*1024:
#   +0 hit triangle index[64] (0xffffffff = miss), +256 distance t[64] (along the
#   unnormalised camera ray), +512 eye-light shade 0xGGGGGGff[64], +768 reserved.
# Pixels within a packet are row-major (ray i = row*8 + col). When no tile is left it
# writes its statistics (STAT_*) to STATS + index*128, sends 1 to its outbound mailbox and
# stops with code 0x2000.
#
# Data layouts come from loader::layout (node: min.xyz, link | max.xyz, count<<2|axis;
# sibling pairs share a 64-byte line; triangle: Wald's projection record + indices).

        .include "layout.inc"

# ---- register names (never starting with sp/lr/rp/fp: the assembler reads those as $1/$0/$127)
        .set ZERO, 10           # 0.0 / 0
        .set ONE, 11            # 1.0f
        .set BIG, 12            # 1e30f
        .set NBIG, 13           # -1e30f
        .set ORIG, 14           # camera origin (x, y, z, 0)
        .set PAT0, 15           # shufb patterns splatting word 0..3
        .set PAT1, 16
        .set PAT2, 17
        .set PAT3, 18
        .set M3, 19             # mask of lane 3
        .set EANODES, 20
        .set EATRIS, 21
        .set EAFB, 22
        .set EACNT, 23
        .set EASTATS, 24
        .set BTAGS, 25          # BVH cache: tags (16 bytes per line), data (64 bytes per line)
        .set BDATA, 26
        .set BMASK, 27
        .set TTAGS, 28          # triangle cache
        .set TDATA, 29
        .set TMASK, 30
        .set DIR00, 31          # camera: ray direction of pixel (0,0); per-pixel steps
        .set DU, 32
        .set DV, 33
        .set TILESX, 34
        .set NTILES, 35
        .set MYID, 36
        .set DUX, 37
        .set DUY, 38
        .set DUZ, 39
        .set DVX, 40
        .set DVY, 41
        .set DVZ, 42
        .set HALF, 43           # 0.5f
# statistics (preferred slot integers)
        .set S_PACKETS, 44
        .set S_STEPS, 45
        .set S_M1SUM, 46        # -(first-ray misses): early hits = steps + M1SUM
        .set S_EESUM, 47        # -(early exits)
        .set S_TRIS, 48         # triangle tests after culling
        .set S_CULLED, 49
        .set S_BMISS, 50
        .set S_TLOOK, 51
        .set S_TMISS, 52
        .set S_LEAVES, 53
# packet state
        .set RLO, 54            # per axis smallest / largest reciprocal direction
        .set RHI, 55
        .set SGN, 56            # all-ones lanes where every direction is negative
        .set MIXED, 57          # all-ones lanes where directions have both signs
        .set PTMAX, 58          # splat: largest hit distance in the packet
        .set ENFILL, 59         # IA-test fill values for mixed axes and lane 3
        .set EXFILL, 60
        .set FMASK, 61          # MIXED | M3
        .set STK, 62            # traversal stack pointer (entries of 16 bytes)
        .set STKBASE, 63
        .set NODE, 64
        .set FIRST, 65          # index of the first active ray
        .set FR_R, 66           # first ray: 1/d (x, y, z, 0) and o/d
        .set FR_OR, 67
        .set FT_ADDR, 68        # address of the first ray's t vector, and its splat pattern
        .set FT_PAT, 69
        .set TILE, 70
        .set PKT, 71
        .set OUTSEL, 72         # which output buffer (0/1024)
        .set TX, 73
        .set TY, 74
        .set COLF0, 75
        .set COLF1, 76

# ---- local-store data
        .data
        .align 7
params:         .space 128
lockbuf:        .space 128
statbuf:        .space 128
        .align 4
k_pat:          .long 0x00010203, 0x00010203, 0x00010203, 0x00010203
                .long 0x04050607, 0x04050607, 0x04050607, 0x04050607
                .long 0x08090a0b, 0x08090a0b, 0x08090a0b, 0x08090a0b
                .long 0x0c0d0e0f, 0x0c0d0e0f, 0x0c0d0e0f, 0x0c0d0e0f
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
k_inc0:         .long 1, 0, 0, 0
k_colf0:        .float 0.0, 1.0, 2.0, 3.0
k_colf1:        .float 4.0, 5.0, 6.0, 7.0
k_ccol:         .float 0.0, 7.0, 0.0, 7.0
k_crow:         .float 0.0, 0.0, 7.0, 7.0
k_plo:          .long 0x00010203, 0x10111213, 0x04050607, 0x14151617
k_phi:          .long 0x08090a0b, 0x18191a1b, 0x0c0d0e0f, 0x1c1d1e1f
k_pa:           .long 0x00010203, 0x04050607, 0x10111213, 0x14151617
k_pb:           .long 0x08090a0b, 0x0c0d0e0f, 0x18191a1b, 0x1c1d1e1f
k_pxyz:         .long 0x00010203, 0x10111213, 0x80808080, 0x80808080   # (a0, b0, 0, 0)
k_pxyz2:        .long 0x00010203, 0x04050607, 0x10111213, 0x80808080   # (a0, a1, b0, 0)
k_entry:        .long 0x00010203, 0x10111213, 0x80808080, 0x80808080
k_bg:           .long 0x000000ff, 0x000000ff, 0x000000ff, 0x000000ff

        .align 4
ray_dx:         .space 256      # structure of arrays, 16 vectors of 4 rays each
ray_dy:         .space 256      # (dx, dy, dz must stay contiguous: k_axoff)
ray_dz:         .space 256
ray_rx:         .space 256
ray_ry:         .space 256
ray_rz:         .space 256
ray_orx:        .space 256
ray_ory:        .space 256
ray_orz:        .space 256
ray_t:          .space 256
ray_id:         .space 256
ray_nd:         .space 256      # cosine numerator: (n.d)/|n| of the hit
ray_invd:       .space 256      # 1/|d|
aos_r:          .space 1024     # per ray (1/dx, 1/dy, 1/dz, 0)
aos_or:         .space 1024     # per ray (ox/dx, oy/dy, oz/dz, 0)
corners:        .space 48       # corner rays' x, y, z (rays 0, 7, 56, 63)
        .align 7
outbuf:         .space 2048     # two packet result blocks, alternating
stack:          .space 2048     # traversal stack: (node, first) per entry
        .align 7
cache_area:                     # carved at start: BVH tags, BVH lines, triangle tags, lines

# ---- code
        .text
        .global _start
_start:
        il      $2, 0
        ori     MYID, $3, 0
        # fetch the parameter block
        ila     $5, params
        il      $6, 128
        il      $7, 0
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $4
        wrch    $MFC_Size, $6
        wrch    $MFC_TagID, $7
        il      $8, 0x40
        wrch    $MFC_Cmd, $8
        il      $8, 1
        wrch    $MFC_WrTagMask, $8
        il      $8, 2
        wrch    $MFC_WrTagUpdate, $8
        rdch    $8, $MFC_RdTagStat

        # constants
        il      ZERO, 0
        ilhu    ONE, 0x3f80
        ilhu    HALF, 0x3f00
        ilhu    BIG, 0x7149
        iohl    BIG, 0xf2ca
        ilhu    NBIG, 0xf149
        iohl    NBIG, 0xf2ca
        ila     $5, k_pat
        lqd     PAT0, 0($5)
        lqd     PAT1, 16($5)
        lqd     PAT2, 32($5)
        lqd     PAT3, 48($5)
        lqa     M3, k_m3
        lqa     COLF0, k_colf0
        lqa     COLF1, k_colf1

        # parameters
        ila     $5, params
        lqd     $6, PARAM_EA_NODES($5)        # quad 0: nodes, tris, fb, counter
        ori     EANODES, $6, 0
        rotqbyi EATRIS, $6, 4
        rotqbyi EAFB, $6, 8
        rotqbyi EACNT, $6, 12
        lqd     $6, PARAM_WIDTH($5)           # quad 1: width, height, tiles_x, num_tiles
        rotqbyi TILESX, $6, 8
        rotqbyi NTILES, $6, 12
        lqd     ORIG, PARAM_ORIGIN($5)
        lqd     DIR00, PARAM_DIR00($5)
        lqd     DU, PARAM_DU($5)
        lqd     DV, PARAM_DV($5)
        andc    ORIG, ORIG, M3
        andc    DIR00, DIR00, M3
        andc    DU, DU, M3
        andc    DV, DV, M3
        shufb   DUX, DU, DU, PAT0
        shufb   DUY, DU, DU, PAT1
        shufb   DUZ, DU, DU, PAT2
        shufb   DVX, DV, DV, PAT0
        shufb   DVY, DV, DV, PAT1
        shufb   DVZ, DV, DV, PAT2
        lqd     $6, PARAM_BVH_LOG2($5)        # quad 6: bvh log2, tri log2, stats EA
        rotqbyi EASTATS, $6, 8
        # carve the caches: lines = 1 << log2
        il      $7, 1
        shl     $8, $7, $6                    # BVH lines
        rotqbyi $9, $6, 4
        shl     $9, $7, $9                    # triangle lines
        ai      BMASK, $8, -1
        ai      TMASK, $9, -1
        ila     BTAGS, cache_area
        shli    $10, $8, 4
        a       BDATA, BTAGS, $10
        shli    $10, $8, 6
        a       TTAGS, BDATA, $10
        shli    $10, $9, 4
        a       TDATA, TTAGS, $10
        il      ZERO, 0
        # invalidate every tag of both caches
        il      $10, -1
        ori     $11, BTAGS, 0
1:      stqd    $10, 0($11)
        ai      $11, $11, 16
        ai      $8, $8, -1
        brnz    $8, 1b
        ori     $11, TTAGS, 0
1:      stqd    $10, 0($11)
        ai      $11, $11, 16
        ai      $9, $9, -1
        brnz    $9, 1b
        il      ZERO, 0
        ilhu    ONE, 0x3f80
        ilhu    BIG, 0x7149
        iohl    BIG, 0xf2ca

        # statistics
        il      S_PACKETS, 0
        il      S_STEPS, 0
        il      S_M1SUM, 0
        il      S_EESUM, 0
        il      S_TRIS, 0
        il      S_CULLED, 0
        il      S_BMISS, 0
        il      S_TLOOK, 0
        il      S_TMISS, 0
        il      S_LEAVES, 0
        ila     STKBASE, stack
        il      OUTSEL, 0

# ---- take the next tile: atomic fetch-and-increment of the shared counter
next_tile:
        ila     $5, lockbuf
        lqa     $9, k_inc0
2:      wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, EACNT
        il      $6, 0xd0                      # getllar
        wrch    $MFC_Cmd, $6
        rdch    $7, $MFC_RdAtomicStat
        lqd     $8, 0($5)
        a       $80, $8, $9
        stqd    $80, 0($5)
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, EACNT
        il      $6, 0xb4                      # putllc
        wrch    $MFC_Cmd, $6
        rdch    $7, $MFC_RdAtomicStat
        andi    $7, $7, 1
        brnz    $7, 2b                        # reservation lost: retry
        clgt    $7, NTILES, $8
        brz     $7, frame_done
        ori     TILE, $8, 0
        # tile coordinates: TY = TILE / TILESX, TX = TILE % TILESX (few tiles per row)
        il      TY, 0
        ori     TX, TILE, 0
3:      clgt    $7, TILESX, TX
        brnz    $7, 4f
        sf      TX, TILESX, TX
        ai      TY, TY, 1
        br      3b
4:      il      PKT, 0

packet_loop:
        # ---- ray generation: d = dir00 + (px0 + col)*du + (py0 + row)*dv
        andi    $5, PKT, 7
        rotmi   $6, PKT, -3
        shli    $7, TX, 6
        shli    $8, TY, 6
        shli    $5, $5, 3
        shli    $6, $6, 3
        a       $5, $5, $7                    # px0
        a       $6, $6, $8                    # py0
        csflt   $5, $5, 0
        csflt   $6, $6, 0
        shufb   $5, $5, $5, PAT0
        shufb   $6, $6, $6, PAT0
        fma     $7, $5, DU, DIR00
        fma     $7, $6, DV, $7                # base direction (x, y, z, 0)
        shufb   $80, $7, $7, PAT0             # bx
        shufb   $81, $7, $7, PAT1             # by
        shufb   $82, $7, $7, PAT2             # bz
        shufb   $83, ORIG, ORIG, PAT0         # ox
        shufb   $84, ORIG, ORIG, PAT1
        shufb   $85, ORIG, ORIG, PAT2
        lqa     $86, k_plo
        lqa     $87, k_phi
        lqa     $88, k_pa
        lqa     $89, k_pb
        # corner rays (0, 7, 56, 63) for the packet frustum
        lqa     $90, k_ccol
        lqa     $91, k_crow
        fma     $92, $91, DVX, $80
        fma     $92, $90, DUX, $92
        fma     $93, $91, DVY, $81
        fma     $93, $90, DUY, $93
        fma     $94, $91, DVZ, $82
        fma     $94, $90, DUZ, $94
        ila     $95, corners
        stqd    $92, 0($95)
        stqd    $93, 16($95)
        stqd    $94, 32($95)

        il      $95, 0                        # byte offset of vector j
        il      $96, 0                        # row (float)
        ila     $97, aos_r
        ila     $98, aos_or
        il      $99, 8                        # rows left
5:      fma     $100, $96, DVX, $80           # row part
        fma     $101, $96, DVY, $81
        fma     $102, $96, DVZ, $82
        il      $103, 2                       # two vectors per row
        ori     $104, COLF0, 0
6:      fma     $105, $104, DUX, $100         # dx
        fma     $106, $104, DUY, $101         # dy
        fma     $107, $104, DUZ, $102         # dz
        frest   $108, $105
        frest   $109, $106
        frest   $110, $107
        fi      $108, $105, $108
        fi      $109, $106, $109
        fi      $110, $107, $110
        fnms    $111, $105, $108, ONE
        fnms    $112, $106, $109, ONE
        fnms    $113, $107, $110, ONE
        fma     $108, $111, $108, $108        # rx (one Newton step)
        fma     $109, $112, $109, $109
        fma     $110, $113, $110, $110
        fm      $111, $83, $108               # ox/dx
        fm      $112, $84, $109
        fm      $113, $85, $110
        fm      $114, $105, $105              # |d|^2
        fma     $114, $106, $106, $114
        fma     $114, $107, $107, $114
        frsqest $115, $114
        fi      $115, $114, $115              # 1/|d|, ~12 bits: enough for shading
        ila     $116, ray_dx
        stqx    $105, $116, $95
        ila     $116, ray_dy
        stqx    $106, $116, $95
        ila     $116, ray_dz
        stqx    $107, $116, $95
        ila     $116, ray_rx
        stqx    $108, $116, $95
        ila     $116, ray_ry
        stqx    $109, $116, $95
        ila     $116, ray_rz
        stqx    $110, $116, $95
        ila     $116, ray_orx
        stqx    $111, $116, $95
        ila     $116, ray_ory
        stqx    $112, $116, $95
        ila     $116, ray_orz
        stqx    $113, $116, $95
        ila     $116, ray_t
        stqx    BIG, $116, $95
        ila     $116, ray_id
        il      $117, -1
        stqx    $117, $116, $95
        ila     $116, ray_nd
        stqx    ZERO, $116, $95
        ila     $116, ray_invd
        stqx    $115, $116, $95
        # transpose (rx, ry, rz) into four per-ray quadwords
        shufb   $117, $108, $109, $86         # rx0 ry0 rx1 ry1
        shufb   $118, $110, ZERO, $86         # rz0 0 rz1 0
        shufb   $119, $108, $109, $87         # rx2 ry2 rx3 ry3
        shufb   $120, $110, ZERO, $87
        shufb   $121, $117, $118, $88         # ray 0
        shufb   $122, $117, $118, $89         # ray 1
        shufb   $123, $119, $120, $88         # ray 2
        shufb   $124, $119, $120, $89         # ray 3
        fm      $125, $121, ORIG
        fm      $126, $122, ORIG
        fm      $127, $123, ORIG
        fm      $117, $124, ORIG
        stqd    $121, 0($97)
        stqd    $122, 16($97)
        stqd    $123, 32($97)
        stqd    $124, 48($97)
        stqd    $125, 0($98)
        stqd    $126, 16($98)
        stqd    $127, 32($98)
        stqd    $117, 48($98)
        ai      $97, $97, 64
        ai      $98, $98, 64
        ai      $95, $95, 16
        ori     $104, COLF1, 0
        ai      $103, $103, -1
        brnz    $103, 6b
        fa      $96, $96, ONE
        ai      $99, $99, -1
        brnz    $99, 5b

        # ---- packet frustum for interval-arithmetic box tests: per-axis 1/d range
        ila     $95, corners
        lqd     $92, 0($95)
        lqd     $93, 16($95)
        lqd     $94, 32($95)
        frest   $100, $92
        frest   $101, $93
        frest   $102, $94
        fi      $100, $92, $100
        fi      $101, $93, $101
        fi      $102, $94, $102
        fnms    $103, $92, $100, ONE
        fnms    $104, $93, $101, ONE
        fnms    $105, $94, $102, ONE
        fma     $100, $103, $100, $100
        fma     $101, $104, $101, $101
        fma     $102, $105, $102, $102
        # min and max over the four corners, per axis (results in every lane):
        # $100..$102 = min of 1/dx, 1/dy, 1/dz; $103..$105 = max
        .irp    R, 100, 101, 102
        rotqbyi $106, $\R, 8
        fcgt    $107, $\R, $106
        selb    $108, $\R, $106, $107
        selb    $109, $106, $\R, $107
        rotqbyi $110, $108, 4
        rotqbyi $111, $109, 4
        fcgt    $112, $108, $110
        fcgt    $113, $111, $109
        selb    $\R, $108, $110, $112
        selb    (\R+3), $109, $111, $113
        .endr
        lqa     $106, k_pxyz
        shufb   $107, $100, $101, $106        # (minx, miny, 0, 0)
        shufb   $108, $103, $104, $106        # (maxx, maxy, 0, 0)
        rotqbyi $109, M3, 4                   # mask of lane 2
        selb    RLO, $107, $102, $109
        selb    RHI, $108, $105, $109
        fcgt    SGN, ZERO, RHI                # every direction negative
        fcgt    MIXED, ZERO, RLO
        andc    MIXED, MIXED, SGN             # signs differ across the packet
        andc    SGN, SGN, M3
        andc    MIXED, MIXED, M3
        or      FMASK, MIXED, M3
        selb    ENFILL, NBIG, ZERO, M3
        ori     PTMAX, BIG, 0
        selb    EXFILL, BIG, PTMAX, M3

        # ---- traversal
        ori     STK, STKBASE, 0
        il      NODE, 0
        il      FIRST, 0
        brsl    $0, set_first

trav:
        hbrr    .Lstep_br, trav               # every step ends by looping back here
        ai      S_STEPS, S_STEPS, 1
        # BVH cache lookup (direct mapped on the sibling pair)
        rotmi   $80, NODE, -1                 # pair
        and     $81, $80, BMASK               # slot
        andi    $82, NODE, 1
        shli    $83, $81, 4
        shli    $84, $81, 6
        shli    $82, $82, 5
        a       $84, $84, $82
        lqx     $85, BTAGS, $83
        a       $86, BDATA, $84               # node address in the cache
        lqd     $87, 0($86)                   # (min, link)
        lqd     $88, 16($86)                  # (max, count << 2 | axis)
        lqd     $89, 0(FT_ADDR)
        ceq     $90, $85, $80
        brz     $90, bvh_miss
bvh_hit:
        shufb   $89, $89, $89, FT_PAT         # first ray's t, every lane
        # first-ray slab test
        fms     $91, $87, FR_R, FR_OR
        fms     $92, $88, FR_R, FR_OR
        # interval-arithmetic test of the whole packet
        selb    $93, $87, $88, SGN            # near planes
        selb    $94, $88, $87, SGN            # far planes
        fcgt    $95, $91, $92
        fs      $93, $93, ORIG
        fs      $94, $94, ORIG
        selb    $96, $91, $92, $95            # per-axis entry
        selb    $97, $92, $91, $95            # per-axis exit
        fm      $98, $93, RLO
        fm      $99, $93, RHI
        fm      $100, $94, RLO
        fm      $101, $94, RHI
        selb    $96, $96, ZERO, M3
        selb    $97, $97, $89, M3
        fcgt    $102, $98, $99
        fcgt    $103, $100, $101
        selb    $104, $98, $99, $102          # packet entry bound per axis
        selb    $105, $101, $100, $103        # packet exit bound per axis
        rotqbyi $106, $96, 8
        rotqbyi $107, $97, 8
        selb    $104, $104, ENFILL, FMASK
        selb    $105, $105, EXFILL, FMASK
        fcgt    $108, $106, $96
        fcgt    $109, $97, $107
        rotqbyi $110, $104, 8
        rotqbyi $111, $105, 8
        selb    $96, $96, $106, $108          # max
        selb    $97, $97, $107, $109          # min
        fcgt    $112, $110, $104
        fcgt    $113, $105, $111
        rotqbyi $106, $96, 4
        rotqbyi $107, $97, 4
        selb    $104, $104, $110, $112
        selb    $105, $105, $111, $113
        fcgt    $108, $106, $96
        fcgt    $109, $97, $107
        rotqbyi $110, $104, 4
        rotqbyi $111, $105, 4
        selb    $96, $96, $106, $108          # first ray: largest entry
        selb    $97, $97, $107, $109          # first ray: smallest exit
        fcgt    $112, $110, $104
        fcgt    $113, $105, $111
        selb    $104, $104, $110, $112
        selb    $105, $105, $111, $113
        fcgt    $114, $96, $97                # first ray misses
        fcgt    $115, $104, $105              # the packet's frustum misses
        rotqbyi $116, $88, 12                 # count << 2 | axis
        a       S_M1SUM, S_M1SUM, $114
        and     $117, $114, $115
        a       S_EESUM, S_EESUM, $117
        andc    $118, $114, $115              # first ray missed, frustum undecided
        brnz    $118, slow                    # the third case: the only one that branches

# ---- one step ends branch-free: descend into the node ($114 = 0) or pop ($114 = -1).
# Both are computed; the push is stored either way (when popping it lands above the top).
step:
        rotmi   $117, $116, -2                # triangle count (0: inner node)
        andc    $119, $117, $114              # a leaf we descend into
        brnz    $119, leaf
        rotqbyi $118, $87, 12                 # first child
        andi    $119, $116, 3                 # split axis
        shli    $119, $119, 2
        rotqby  $120, FR_R, $119              # first ray's 1/d on that axis
        fcgt    $121, ZERO, $120              # -1 when it points down the axis
        lqd     $81, -16(STK)                 # the entry a pop takes
        sf      $124, $121, $118              # near child: first + (negative)
        a       $122, $118, $121
        ai      $122, $122, 1                 # far child
        lqa     $123, k_entry
        shufb   $123, $122, FIRST, $123
        ceq     $80, STK, STKBASE
        stqd    $123, 0(STK)
        ai      $125, STK, 16
        ai      $126, STK, -16
        and     $80, $80, $114                # popping an empty stack: the packet is done
        brnz    $80, packet_done
        rotqbyi $82, $81, 4                   # popped first active ray
        selb    STK, $125, $126, $114
        selb    NODE, $124, $81, $114
        selb    $82, FIRST, $82, $114
        ceq     $83, $82, FIRST
        brz     $83, first_changed
.Lstep_br:
        br      trav
first_changed:
        ori     FIRST, $82, 0
        brsl    $0, set_first
        br      trav

        # ---- neither test decided: look for the first ray (from FIRST on) that hits
slow:

        # ---- neither test decided: look for the first ray (from FIRST on) that hits
        shufb   $80, $87, $87, PAT0           # box planes, splat
        shufb   $81, $87, $87, PAT1
        shufb   $82, $87, $87, PAT2
        shufb   $83, $88, $88, PAT0
        shufb   $84, $88, $88, PAT1
        shufb   $85, $88, $88, PAT2
        rotmi   $86, FIRST, -2
        shli    $86, $86, 4                   # byte offset of FIRST's vector
        andi    $90, FIRST, 3
        shli    $90, $90, 4
        ila     $91, k_lanege
        lqx     $92, $91, $90                 # lanes at or after FIRST
7:      ila     $93, ray_rx
        lqx     $94, $93, $86
        ila     $93, ray_ry
        lqx     $95, $93, $86
        ila     $93, ray_rz
        lqx     $96, $93, $86
        ila     $93, ray_orx
        lqx     $97, $93, $86
        ila     $93, ray_ory
        lqx     $98, $93, $86
        ila     $93, ray_orz
        lqx     $99, $93, $86
        ila     $93, ray_t
        lqx     $100, $93, $86
        fms     $101, $80, $94, $97
        fms     $102, $83, $94, $97
        fms     $103, $81, $95, $98
        fms     $104, $84, $95, $98
        fms     $105, $82, $96, $99
        fms     $106, $85, $96, $99
        fcgt    $107, $101, $102
        fcgt    $108, $103, $104
        fcgt    $109, $105, $106
        selb    $110, $101, $102, $107        # entry x
        selb    $111, $102, $101, $107        # exit x
        selb    $112, $103, $104, $108
        selb    $113, $104, $103, $108
        selb    $114, $105, $106, $109
        selb    $115, $106, $105, $109
        fcgt    $107, $112, $110
        fcgt    $108, $111, $113
        selb    $110, $110, $112, $107
        selb    $111, $111, $113, $108
        fcgt    $107, $114, $110
        fcgt    $108, $111, $115
        selb    $110, $110, $114, $107
        selb    $111, $111, $115, $108
        fcgt    $107, ZERO, $110
        fcgt    $108, $111, $100
        selb    $110, $110, ZERO, $107        # entry >= 0
        selb    $111, $111, $100, $108        # exit <= t
        fcgt    $107, $110, $111              # misses
        andc    $107, $92, $107               # active lanes that hit
        gb      $108, $107
        brnz    $108, 8f
        lqa     $92, k_lanege                 # later vectors: all lanes
        ai      $86, $86, 16
        ceqi    $109, $86, 256
        brz     $109, 7b
        il      $114, -1                      # no ray hits the box: pop
        br      step
8:      clz     $108, $108                    # first lane = clz - 28
        ai      $108, $108, -28
        rotmi   FIRST, $86, -2
        a       FIRST, FIRST, $108
        brsl    $0, set_first
        rotqbyi $116, $88, 12
        il      $114, 0                       # descend with the new first ray
        br      step

bvh_miss:
        # $80 pair, $81 slot, $83 slot*16, $86 node address in the cache line
        ai      S_BMISS, S_BMISS, 1
        stqx    $80, BTAGS, $83               # the line now holds this pair
        shli    $85, $80, 6
        a       $85, $85, EANODES             # effective address of the pair
        shli    $91, $81, 6
        a       $92, BDATA, $91               # the cache line
        wrch    $MFC_LSA, $92
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $85
        il      $91, 64
        wrch    $MFC_Size, $91
        il      $91, 1
        wrch    $MFC_TagID, $91
        il      $91, 0x40
        wrch    $MFC_Cmd, $91
        il      $91, 2
        wrch    $MFC_WrTagMask, $91
        wrch    $MFC_WrTagUpdate, $91
        rdch    $91, $MFC_RdTagStat
        lqd     $87, 0($86)
        lqd     $88, 16($86)
        lqd     $89, 0(FT_ADDR)
        br      bvh_hit

# ---- set_first: derive the first ray's cached data from FIRST
set_first:
        shli    $80, FIRST, 4
        ila     $81, aos_r
        lqx     FR_R, $81, $80
        ila     $81, aos_or
        lqx     FR_OR, $81, $80
        rotmi   $82, FIRST, -2
        shli    $82, $82, 4
        ila     $81, ray_t
        a       FT_ADDR, $81, $82
        andi    $83, FIRST, 3
        shli    $83, $83, 4
        ila     $81, k_pat
        lqx     FT_PAT, $81, $83
        bi      $0

# ---- leaf: test the active rays against each triangle of the leaf
leaf:
        ai      S_LEAVES, S_LEAVES, 1
        rotqbyi $78, $87, 12                  # first triangle
        ori     $79, $117, 0                  # count
tri_loop:
        ai      S_TLOOK, S_TLOOK, 1
        and     $80, $78, TMASK
        shli    $81, $80, 4
        shli    $82, $80, 6
        lqx     $83, TTAGS, $81
        a       $84, TDATA, $82
        ceq     $85, $83, $78
        brz     $85, tri_miss                 # hits fall through
.Ltri_hit:
        lqd     $86, TRI_N_U($84)              # (n_u, n_v, n_d, k)
        lqd     $87, TRI_B_NU($84)             # (b_nu, b_nv, b_d, -)
        lqd     $88, TRI_C_NU($84)             # (c_nu, c_nv, c_d, -)
        rotqbyi $89, $86, 12                  # k
        shli    $89, $89, 4
        ila     $90, k_axoff
        lqx     $91, $90, $89                 # (k, u, v) array offsets
        ila     $90, k_kuv
        lqx     $92, $90, $89
        shufb   $92, ORIG, ORIG, $92          # origin in (k, u, v) order
        # per-triangle splats, live through the ray loop
        shufb   $2, $86, $86, PAT0            # n_u
        shufb   $3, $86, $86, PAT1            # n_v
        shufb   $93, $86, $86, PAT2           # n_d
        shufb   $5, $87, $87, PAT0            # b_nu
        shufb   $6, $87, $87, PAT1            # b_nv
        shufb   $7, $87, $87, PAT2            # b_d
        shufb   $8, $88, $88, PAT0            # c_nu
        shufb   $9, $88, $88, PAT1            # c_nv
        shufb   $120, $88, $88, PAT2          # c_d
        shufb   $94, $92, $92, PAT0           # o_k
        shufb   $121, $92, $92, PAT1          # o_u
        shufb   $122, $92, $92, PAT2          # o_v
        fs      $4, $93, $94
        fnms    $4, $2, $121, $4
        fnms    $4, $3, $122, $4              # num = n_d - o_k - n_u o_u - n_v o_v
        fm      $95, $2, $2
        fma     $95, $3, $3, $95
        fa      $95, $95, ONE
        frsqest $96, $95
        fi      $123, $95, $96                # 1/|n|, n = (1, n_u, n_v) in (k, u, v)
        shufb   $124, $78, $78, PAT0          # triangle index
        ila     $97, ray_dx
        rotqbyi $98, $91, 4
        rotqbyi $99, $91, 8
        a       $125, $97, $91                # base of d_k
        a       $126, $97, $98                # d_u
        a       $127, $97, $99                # d_v
        # frustum culling with the packet's corner rays (0, 7, 56, 63)
        ila     $97, corners
        rotmi   $100, $91, -4
        rotmi   $101, $98, -4
        rotmi   $102, $99, -4
        lqx     $103, $97, $100               # corner d_k
        lqx     $104, $97, $101               # corner d_u
        lqx     $105, $97, $102               # corner d_v
        fma     $106, $2, $104, $103
        fma     $106, $3, $105, $106          # den = n.d
        frest   $107, $106
        fi      $107, $106, $107
        fnms    $108, $106, $107, ONE
        fma     $107, $108, $107, $107
        fm      $107, $4, $107                # t
        fma     $108, $107, $104, $121        # hit u
        fma     $109, $107, $105, $122        # hit v
        fma     $110, $5, $108, $7
        fma     $110, $6, $109, $110          # beta
        fma     $111, $8, $108, $120
        fma     $111, $9, $109, $111          # gamma
        fa      $112, $110, $111
        fcgt    $113, $107, ZERO              # in front
        fcgt    $114, ZERO, $110
        fcgt    $115, ZERO, $111
        fcgt    $116, $112, ONE
        and     $114, $114, $113
        and     $115, $115, $113
        and     $116, $116, $113
        gb      $113, $113
        gb      $114, $114
        gb      $115, $115
        gb      $116, $116
        ceqi    $113, $113, 0                 # every corner behind
        ceqi    $114, $114, 15                # every corner outside one edge
        ceqi    $115, $115, 15
        ceqi    $116, $116, 15
        or      $113, $113, $114
        or      $115, $115, $116
        or      $113, $113, $115
        sf      S_CULLED, $113, S_CULLED      # +1 when culled
        brnz    $113, tri_next
        ai      S_TRIS, S_TRIS, 1

        # the active rays, four vectors (16 rays) per pass, from FIRST's group on
        rotmi   $119, FIRST, -4
        shli    $119, $119, 6                 # byte offset of the first group
ray_loop:
        hbrr    .Lray_br, ray_loop
        .irp    J, 0, 1, 2, 3
        lqx     (\J+80), $125, $119          # d_k
        lqx     (\J+84), $126, $119          # d_u
        lqx     (\J+88), $127, $119          # d_v
        ai      $119, $119, 16
        .endr
        ai      $119, $119, -64
        .irp    J, 0, 1, 2, 3
        fma     (\J+92), $2, (\J+84), (\J+80)
        .endr
        .irp    J, 0, 1, 2, 3
        fma     (\J+92), $3, (\J+88), (\J+92)   # den
        .endr
        .irp    J, 0, 1, 2, 3
        frest   (\J+96), (\J+92)
        .endr
        .irp    J, 0, 1, 2, 3
        fi      (\J+96), (\J+92), (\J+96)
        .endr
        .irp    J, 0, 1, 2, 3
        fnms    (\J+80), (\J+92), (\J+96), ONE
        .endr
        .irp    J, 0, 1, 2, 3
        fma     (\J+96), (\J+80), (\J+96), (\J+96)
        .endr
        .irp    J, 0, 1, 2, 3
        fm      (\J+96), $4, (\J+96)       # t
        .endr
        .irp    J, 0, 1, 2, 3
        fma     (\J+80), (\J+96), (\J+84), $121   # hit u
        fma     (\J+84), (\J+96), (\J+88), $122   # hit v
        .endr
        .irp    J, 0, 1, 2, 3
        fma     (\J+88), $5, (\J+80), $7
        fma     (\J+80), $8, (\J+80), $120
        .endr
        .irp    J, 0, 1, 2, 3
        fma     (\J+88), $6, (\J+84), (\J+88)     # beta
        fma     (\J+80), $9, (\J+84), (\J+80)     # gamma
        .endr
        ila     $116, ray_t
        a       $116, $116, $119
        ila     $117, ray_id
        a       $117, $117, $119
        ila     $118, ray_nd
        a       $118, $118, $119
        .irp    J, 0, 1, 2, 3
        lqd     (\J+100), \J*16($116)       # current t
        fa      (\J+84), (\J+88), (\J+80)  # beta + gamma
        .endr
        .irp    J, 0, 1, 2, 3
        or      (\J+88), (\J+88), (\J+80)  # sign bit: beta < 0 or gamma < 0
        fcgt    (\J+84), (\J+84), ONE       # beta + gamma > 1
        .endr
        .irp    J, 0, 1, 2, 3
        fcgt    (\J+80), (\J+100), (\J+96) # t < current
        fcgt    (\J+104), (\J+96), ZERO     # t > 0
        .endr
        .irp    J, 0, 1, 2, 3
        rotmai  (\J+88), (\J+88), -31       # all ones when negative
        and     (\J+80), (\J+80), (\J+104)
        .endr
        .irp    J, 0, 1, 2, 3
        or      (\J+88), (\J+88), (\J+84)
        .endr
        .irp    J, 0, 1, 2, 3
        andc    (\J+80), (\J+80), (\J+88)  # hit
        .endr
        .irp    J, 0, 1, 2, 3
        lqd     (\J+104), \J*16($117)
        lqd     (\J+108), \J*16($118)
        fm      (\J+92), (\J+92), $123      # n.d / |n|
        selb    (\J+100), (\J+100), (\J+96), (\J+80)
        .endr
        .irp    J, 0, 1, 2, 3
        selb    (\J+104), (\J+104), $124, (\J+80)
        selb    (\J+108), (\J+108), (\J+92), (\J+80)
        stqd    (\J+100), \J*16($116)
        .endr
        .irp    J, 0, 1, 2, 3
        stqd    (\J+104), \J*16($117)
        stqd    (\J+108), \J*16($118)
        .endr
        ai      $119, $119, 64
        ceqi    $112, $119, 256
.Lray_br:
        brz     $112, ray_loop
tri_next:
        ai      $78, $78, 1
        ai      $79, $79, -1
        brnz    $79, tri_loop
        # the packet's largest t shrinks as rays hit: refresh the IA exit bound
        hbrr    .Lleaf_br, step
        ila     $80, ray_t
        lqd     $81, 0($80)
        il      $82, 15
10:     ai      $80, $80, 16
        lqd     $83, 0($80)
        fcgt    $84, $83, $81
        selb    $81, $81, $83, $84
        ai      $82, $82, -1
        brnz    $82, 10b
        rotqbyi $83, $81, 8
        fcgt    $84, $83, $81
        selb    $81, $81, $83, $84
        rotqbyi $83, $81, 4
        fcgt    $84, $83, $81
        selb    PTMAX, $81, $83, $84
        selb    EXFILL, BIG, PTMAX, M3
        il      $114, -1                      # then pop
.Lleaf_br:
        br      step

tri_miss:
        # triangle cache miss: fetch the 64-byte record, then test it
        ai      S_TMISS, S_TMISS, 1
        stqx    $78, TTAGS, $81
        shli    $85, $78, 6
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
packet_done:
        ai      S_PACKETS, S_PACKETS, 1
        ila     $80, outbuf
        a       $80, $80, OUTSEL
        # wait until this buffer's previous transfer (tag 2 + OUTSEL/1024) is done
        rotmi   $81, OUTSEL, -10
        ai      $81, $81, 2
        il      $82, 1
        shl     $82, $82, $81
        wrch    $MFC_WrTagMask, $82
        il      $83, 2
        wrch    $MFC_WrTagUpdate, $83
        rdch    $83, $MFC_RdTagStat
        ila     $84, ray_id
        ila     $85, ray_t
        ila     $86, ray_nd
        ila     $87, ray_invd
        lqa     $88, k_bg
        il      $89, 0
        il      $90, 255
        il      $91, 16
11:     lqx     $92, $84, $89
        lqx     $93, $85, $89
        lqx     $94, $86, $89
        lqx     $95, $87, $89
        fm      $96, $94, $95                 # cosine (signed)
        andi    $96, $96, -1
        shli    $96, $96, 1
        rotmi   $96, $96, -1                  # |cosine|
        cfltu   $96, $96, 8                   # * 256
        clgt    $97, $96, $90
        selb    $96, $96, $90, $97            # clamp to 255
        shli    $98, $96, 8
        or      $98, $98, $96
        shli    $99, $98, 16
        or      $98, $98, $99
        shli    $98, $98, 8
        ori     $98, $98, 0xff                # gray, opaque
        ceqi    $97, $92, -1
        selb    $98, $98, $88, $97            # background for misses
        a       $99, $80, $89
        stqd    $92, 0($99)
        stqd    $93, 256($99)
        stqd    $98, 512($99)
        stqd    ZERO, 768($99)
        ai      $89, $89, 16
        ai      $91, $91, -1
        brnz    $91, 11b
        # put the 1 KiB block to FB + (tile*64 + packet)*1024
        shli    $92, TILE, 6
        a       $92, $92, PKT
        shli    $92, $92, 10
        a       $92, $92, EAFB
        wrch    $MFC_LSA, $80
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $92
        il      $93, 1024
        wrch    $MFC_Size, $93
        wrch    $MFC_TagID, $81
        il      $93, 0x20
        wrch    $MFC_Cmd, $93
        il      $93, 1024
        xor     OUTSEL, OUTSEL, $93
        ai      PKT, PKT, 1
        ceqi    $93, PKT, 64
        brz     $93, packet_loop
        br      next_tile

# ---- no tiles left: statistics, end-of-frame message, stop
frame_done:
        il      $80, 12                       # tags 2 and 3: the last results
        wrch    $MFC_WrTagMask, $80
        il      $80, 2
        wrch    $MFC_WrTagUpdate, $80
        rdch    $80, $MFC_RdTagStat
        ila     $80, statbuf
        lqa     $81, k_entry
        shufb   $82, S_PACKETS, S_STEPS, $81
        stqd    $82, STAT_PACKETS($80)        # (packets, steps, -, -)
        shufb   $82, S_M1SUM, S_EESUM, $81
        stqd    $82, STAT_M1SUM($80)
        shufb   $82, S_TRIS, S_CULLED, $81
        stqd    $82, STAT_TRIS($80)
        shufb   $82, S_BMISS, S_LEAVES, $81
        stqd    $82, STAT_BMISS($80)
        shufb   $82, S_TLOOK, S_TMISS, $81
        stqd    $82, STAT_TLOOK($80)
        shli    $83, MYID, 7
        a       $83, $83, EASTATS
        wrch    $MFC_LSA, $80
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $83
        il      $84, 128
        wrch    $MFC_Size, $84
        il      $84, 4
        wrch    $MFC_TagID, $84
        il      $84, 0x20
        wrch    $MFC_Cmd, $84
        il      $84, 16
        wrch    $MFC_WrTagMask, $84
        il      $84, 2
        wrch    $MFC_WrTagUpdate, $84
        rdch    $84, $MFC_RdTagStat
        il      $84, 1
        wrch    $SPU_WrOutMbox, $84
        stop    0x2000
