# shade.s — shading of a traced 8x8 packet (paper section 7): the i-set, the vertex and
# material caches, multi-pass diffuse shading and the 32-bit colour frame buffer.
#
# `brsl $0, shade_packet` once a packet is traced. In: $68 = local-store address of the
# packet's ray arrays (16 vectors of 4 rays each: dx, dy, dz at +0, +256, +512, t at
# +CTX_RAY_T, the hit triangle's record per ray or -1 at +CTX_RAY_ID), $69 = the packet number
# (tile * 64 + packet), the camera origin and the shading addresses in params. Out: the
# packet's 64 pixels 0xRRGGBBff, row-major, put to ShadingBlock.ea_colour + packet * 256
# (tags 6/7, alternating; the frame's end waits for both). Model: loader/src/shading.rs.
# Keeps $1..$65 (the frame's registers; reads ZERO and EATRIS), uses $66..$127 and $0.
#
# 1. The i-set: per intersection packet of 4 rays, a flag says whether all 4 hit the same
#    triangle; then its record (64 bytes: the barycentric rows and, in the spare 16 bytes,
#    the vertex and material indices) and its three vertex normals are fetched once and
#    copied to the other lanes. Otherwise per lane. Vertices go through a direct-mapped
#    cache of 64-byte records (ShadingBlock.vertex_cache_log2 entries). The lanes' rows are
#    transposed, and per ray the barycentrics of the hit point o + t d (the projection of
#    the record, as the hit test computed them), the interpolated normal facing the eye and
#    the material are stored structure-of-arrays.
# 2. Multi-pass shading: the first material still referenced in the i-set is looked up in
#    the direct-mapped material cache, its diffuse shader runs over all 16 intersection
#    packets under the mask of its rays, and then clears their references; until none is
#    left (the paper's 1-2 passes per packet).
#
# The shading area (SH_AREA_BYTES of local store, at the address the host puts in params
# beside the shading block's, above everything the kernel carves) is set up on the first
# call: the block is fetched, the lights splatted, the caches' tags cleared. Its counters (SH_STATS, one
# per quadword, word 0) are read by the host from local store, as the PPE reads an SPE's
# memory-mapped local store.

        .set SH_FLAG, 0                 # "SHAD" once set up
        .set SH_STATS, 16               # 10 counters, one per quadword:
        .set SHS_GROUPS, 0              #   intersection packets with a hit
        .set SHS_SAME, 16               #   ... whose 4 rays hit the same triangle
        .set SHS_PASSES, 32             #   shading passes
        .set SHS_PACKETS, 48            #   packets shaded
        .set SHS_VLOOK, 64              #   vertex cache lookups (3 per record: the host's), misses
        .set SHS_VMISS, 80
        .set SHS_MLOOK, 96              #   material cache lookups, misses
        .set SHS_MMISS, 112
        .set SHS_TLOOK, 128             #   triangle records looked up in the traversal's
        .set SHS_TMISS, 144             #   triangle cache, and fetched past it
        .set SH_BLOCK, 256              # the shading block (SHADING_BLOCK_BYTES)
        .set SH_LIGHTS, 640             # per light: px, py, pz, r, g, b splats (96 bytes)
        .set SH_SCRATCH, 1408           # the normals' columns (144 bytes), the same flag
        .set SH_SAME, SH_SCRATCH+240
        .set SH_STAGE, 1664             # per lane: the triangle record (64 bytes)
        .set SH_NRM, 1920               # per lane: n0, n1, n2, - (64 bytes)
        .set SH_NX, 2176                # the i-set, 16 vectors each: normal,
        .set SH_NY, 2432
        .set SH_NZ, 2688
        .set SH_PX, 2944                # hit point,
        .set SH_PY, 3200
        .set SH_PZ, 3456
        .set SH_MAT, 3712               # material (-1: none left)
        .set SH_OUT, 3968               # two colour blocks, alternating
        .set SH_VIS, 4480               # per light: visibility masks (256 bytes)
        .set SH_VTAGS, 6528             # vertex cache tags (up to 256 x 16)
        .set SH_VDATA, 10624            # vertex cache lines (up to 256 x 64)
        .set SH_MTAGS, 27008            # material cache tags (up to 256 x 16)
        .set SH_MDATA, 31104            # material cache lines (up to 256 x 32)
        .set SH_AREA_BYTES, 39296
        .set SH_TAG, 5
        .set CTX_RAY_T, 1536
        .set CTX_RAY_ID, 1792                  # fetches; colour output on 6 and 7

# rt = ra + an area offset (beyond ai's 10 bits; $96 is the scratch)
        .macro  SH_ADDI rt, ra, off
        il      $96, \off
        a       \rt, \ra, $96
        .endm

# get LS <- EA, SIZE bytes on tag SH_TAG and wait (registers: ls, ea, size, scratch)
        .macro  SH_GET ls, ea, size, tmp
        wrch    $MFC_LSA, \ls
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, \ea
        wrch    $MFC_Size, \size
        il      \tmp, SH_TAG
        wrch    $MFC_TagID, \tmp
        il      \tmp, 0x40
        wrch    $MFC_Cmd, \tmp
        il      \tmp, 1 << SH_TAG
        wrch    $MFC_WrTagMask, \tmp
        il      \tmp, 2
        wrch    $MFC_WrTagUpdate, \tmp
        rdch    \tmp, $MFC_RdTagStat
        .endm

# counter += 1 (a quadword of SH_STATS; $66 = area)
        .macro  SH_COUNT which, tmp
        lqd     \tmp, SH_STATS+\which($66)
        ai      \tmp, \tmp, 1
        stqd    \tmp, SH_STATS+\which($66)
        .endm

# 4x4 transpose of the rows a, b, c, d into the columns c0..c3 ($117..$119, $98: patterns)
        .macro  SH_TRANSPOSE a, b, c, d, c0, c1, c2, c3, t0, t1, t2, t3
        shufb   \t0, \a, \b, $117
        shufb   \t1, \c, \d, $117
        shufb   \t2, \a, \b, $118
        shufb   \t3, \c, \d, $118
        shufb   \c0, \t0, \t1, $119
        shufb   \c1, \t0, \t1, $98
        shufb   \c2, \t2, \t3, $119
        shufb   \c3, \t2, \t3, $98
        .endm

# vertex I of lane LANE: the normal of vertex word I of $80 (the record's spare quad) to
# SH_NRM + LANE*64 + I*16, through the vertex cache ($104 index mask, $115 tags, $116
# lines); a miss calls sh_vertex_miss ($114) without a taken branch on the hit path
        .macro  SH_VERTEX lane, i
        rotqbyi $81, $80, 4*\i
        and     $82, $81, $104
        shli    $83, $82, 4
        shli    $84, $82, 6
        a       $83, $83, $115                # tag address
        a       $84, $84, $116                # line address
        lqd     $85, 0($83)
        ila     $88, 1f
        ceq     $86, $85, $81
        biz     $86, $114
1:      lqd     $85, 16($84)
        stqd    $85, SH_NRM+\lane*64+\i*16($66)
        .endm

# lane LANE of the intersection packet in $70 (ids): its record to SH_STAGE + LANE*64 and
# its vertex normals to SH_NRM + LANE*64 (nothing for a miss); a record the traversal's
# triangle cache does not hold is fetched by sh_tri_miss ($106)
        .macro  SH_FETCH lane
        rotqbyi $80, $70, 4*\lane
        ceqi    $81, $80, -1
        brnz    $81, 3f
        SH_COUNT SHS_TLOOK, $84
        SH_ADDI $82, $66, SH_STAGE+\lane*64
        ila     $88, 5f
        .ifdef  TTAGS
        and     $81, $80, TMASK
        shli    $83, $81, 4
        lqx     $83, TTAGS, $83
        shli    $85, $81, 6
        a       $85, $85, TDATA
        ceq     $83, $83, $80
        biz     $83, $106
        .irp    Q, 0, 16, 32, 48
        lqd     $83, \Q($85)
        stqd    $83, \Q($82)
        .endr
        .else
        bi      $106
        .endif
5:      lqd     $80, SH_STAGE+\lane*64+48($66)
        SH_VERTEX \lane, 0
        SH_VERTEX \lane, 1
        SH_VERTEX \lane, 2
3:
        .endm

        .text
        .align  4
sh_const:
        .long   0x00010203, 0x10111213, 0x04050607, 0x14151617     # +0   transpose: lo pairs
        .long   0x08090a0b, 0x18191a1b, 0x0c0d0e0f, 0x1c1d1e1f     # +16  hi pairs
        .long   0x00010203, 0x04050607, 0x10111213, 0x14151617     # +32  first halves
        .long   0x08090a0b, 0x0c0d0e0f, 0x18191a1b, 0x1c1d1e1f     # +48  second halves
        .long   0x00010203, 0x00010203, 0x00010203, 0x00010203     # +64  splat word 0
        .long   0x04050607, 0x04050607, 0x04050607, 0x04050607     # +80  splat word 1
        .long   0x08090a0b, 0x08090a0b, 0x08090a0b, 0x08090a0b     # +96  splat word 2
        .long   AMBIENT_BITS, AMBIENT_BITS, AMBIENT_BITS, AMBIENT_BITS # +112
        .float  255.0, 255.0, 255.0, 255.0                         # +128
        .float  0.5, 0.5, 0.5, 0.5                                 # +144
        .float  1.5, 1.5, 1.5, 1.5                                 # +160
        .float  1.0, 1.0, 1.0, 1.0                                 # +176
        .long   0x000000ff, 0x000000ff, 0x000000ff, 0x000000ff     # +192 a miss: black

        .align  3
shade_packet:
        ori     $99, $68, 0                   # the rays
        ori     $97, $69, 0                   # the packet number
        ila     $70, params
        lqd     $71, PARAM_SHADING_QUAD($70)
        rotqbyi $71, $71, PARAM_SHADING_ROT   # shading block EA, area
        rotqbyi $66, $71, 4                   # the shading area
        lqd     $67, SH_FLAG($66)
        ilhu    $68, 0x5348
        iohl    $68, 0x4144                   # "SHAD"
        ceq     $69, $67, $68
        brnz    $69, .Lsh_ready

        # ---- first call: fetch the block, splat the lights, clear counters and caches
        stqd    $68, SH_FLAG($66)
        SH_ADDI $72, $66, SH_BLOCK
        il      $73, SHADING_BLOCK_BYTES
        SH_GET  $72, $71, $73, $74
        il      $70, 10
        SH_ADDI $71, $66, SH_STATS
1:      stqd    ZERO, 0($71)
        ai      $71, $71, 16
        ai      $70, $70, -1
        brnz    $70, 1b
        ila     $90, sh_const
        lqd     $91, 64($90)
        lqd     $92, 80($90)
        lqd     $93, 96($90)
        lqd     $70, SH_BLOCK($66)
        rotqbyi $71, $70, SHB_LIGHT_COUNT
        SH_ADDI $72, $66, SH_BLOCK+SHB_LIGHTS
        SH_ADDI $73, $66, SH_LIGHTS
        brz     $71, 2f
1:      lqd     $74, 0($72)
        lqd     $75, 16($72)
        shufb   $76, $74, $74, $91
        stqd    $76, 0($73)
        shufb   $76, $74, $74, $92
        stqd    $76, 16($73)
        shufb   $76, $74, $74, $93
        stqd    $76, 32($73)
        shufb   $76, $75, $75, $91
        stqd    $76, 48($73)
        shufb   $76, $75, $75, $92
        stqd    $76, 64($73)
        shufb   $76, $75, $75, $93
        stqd    $76, 80($73)
        ai      $72, $72, SHB_LIGHT_BYTES
        ai      $73, $73, 96
        ai      $71, $71, -1
        brnz    $71, 1b
2:      il      $74, -1                       # every light visible (no shadow rays)
        SH_ADDI $72, $66, SH_VIS
        il      $71, 8 * 16
1:      stqd    $74, 0($72)
        ai      $72, $72, 16
        ai      $71, $71, -1
        brnz    $71, 1b
        lqd     $70, SH_BLOCK+SHB_MODE($66)   # mode, early, vertex log2, material log2
        il      $74, -1
        il      $75, 1
        rotqbyi $71, $70, 8
        shl     $71, $75, $71                 # vertex entries
        SH_ADDI $72, $66, SH_VTAGS
1:      stqd    $74, 0($72)
        ai      $72, $72, 16
        ai      $71, $71, -1
        brnz    $71, 1b
        rotqbyi $71, $70, 12
        shl     $71, $75, $71                 # material entries
        SH_ADDI $72, $66, SH_MTAGS
1:      stqd    $74, 0($72)
        ai      $72, $72, 16
        ai      $71, $71, -1
        brnz    $71, 1b

.Lsh_ready:
        lqd     $70, SH_BLOCK($66)            # vertices, materials, colour, lights
        ori     $100, $70, 0
        rotqbyi $101, $70, 4
        rotqbyi $102, $70, 8
        rotqbyi $103, $70, 12
        lqd     $70, SH_BLOCK+SHB_MODE($66)
        il      $75, 1
        rotqbyi $71, $70, 8
        shl     $104, $75, $71
        ai      $104, $104, -1                # vertex cache index mask
        rotqbyi $71, $70, 12
        shl     $105, $75, $71
        ai      $105, $105, -1                # material cache index mask
        ila     $90, sh_const
        lqd     $117, 0($90)
        lqd     $118, 16($90)
        lqd     $119, 32($90)
        lqd     $98, 48($90)
        lqd     $91, 64($90)
        ila     $70, params
        lqd     $71, PARAM_ORIGIN($70)
        shufb   $107, $71, $71, $91           # origin x, y, z splats
        lqd     $92, 80($90)
        shufb   $108, $71, $71, $92
        lqd     $93, 96($90)
        shufb   $109, $71, $71, $93
        SH_ADDI $111, $99, CTX_RAY_ID
        SH_ADDI $112, $99, CTX_RAY_T
        ori     $113, $99, 0

        # ---- 1. the i-set
        ila     $114, sh_vertex_miss
        ila     $106, sh_tri_miss
        SH_ADDI $115, $66, SH_VTAGS
        SH_ADDI $116, $66, SH_VDATA
        il      $67, 0                        # intersection packet * 16
.Lsh_group:
        lqx     $70, $111, $67                # ids
        ceqi    $78, $70, -1                  # misses
        gb      $72, $78
        ceqi    $73, $72, 15
        brnz    $73, .Lsh_group_empty
        SH_COUNT SHS_GROUPS, $74
        shufb   $74, $70, $70, $91
        ceq     $75, $70, $74
        gb      $75, $75
        ceqi    $75, $75, 15                  # the same triangle in all four lanes
        stqd    $75, SH_SAME($66)             # (kept over the fetches)
        SH_FETCH 0
        lqd     $75, SH_SAME($66)
        brz     $75, .Lsh_lanes
        SH_COUNT SHS_SAME, $74
        hbrr    .Lsh_copied, .Lsh_fetched
        .irp    L, 1, 2, 3
        .irp    Q, 0, 16, 32, 48
        lqd     $74, SH_STAGE+\Q($66)
        stqd    $74, SH_STAGE+\L*64+\Q($66)
        .endr
        .irp    Q, 0, 16, 32
        lqd     $74, SH_NRM+\Q($66)
        stqd    $74, SH_NRM+\L*64+\Q($66)
        .endr
        .endr
.Lsh_copied:
        br      .Lsh_fetched
.Lsh_lanes:
        SH_FETCH 1
        SH_FETCH 2
        SH_FETCH 3
.Lsh_fetched:
        # the lanes' records and normals as columns
        lqd     $70, SH_STAGE+0($66)
        lqd     $71, SH_STAGE+64($66)
        lqd     $72, SH_STAGE+128($66)
        lqd     $73, SH_STAGE+192($66)
        SH_TRANSPOSE $70, $71, $72, $73, $74, $75, $76, $77, $80, $81, $82, $83
        ori     $120, $77, 0                  # k
        lqd     $70, SH_STAGE+16($66)
        lqd     $71, SH_STAGE+80($66)
        lqd     $72, SH_STAGE+144($66)
        lqd     $73, SH_STAGE+208($66)
        SH_TRANSPOSE $70, $71, $72, $73, $121, $122, $123, $77, $80, $81, $82, $83
        lqd     $70, SH_STAGE+32($66)
        lqd     $71, SH_STAGE+96($66)
        lqd     $72, SH_STAGE+160($66)
        lqd     $73, SH_STAGE+224($66)
        SH_TRANSPOSE $70, $71, $72, $73, $124, $125, $126, $77, $80, $81, $82, $83
        lqd     $70, SH_STAGE+48($66)
        lqd     $71, SH_STAGE+112($66)
        lqd     $72, SH_STAGE+176($66)
        lqd     $73, SH_STAGE+240($66)
        SH_TRANSPOSE $70, $71, $72, $73, $74, $75, $76, $127, $80, $81, $82, $83
        or      $127, $127, $78               # misses: no material
        SH_ADDI $74, $66, SH_MAT
        stqx    $127, $74, $67                # materials (-1 for misses)
        # the hit point o + t d and its projection (u, v) by k
        lqx     $70, $112, $67                # t
        lqx     $71, $113, $67                # dx
        ai      $74, $113, 256
        lqx     $72, $74, $67                 # dy
        SH_ADDI $74, $113, 512
        lqx     $73, $74, $67                 # dz
        fma     $84, $70, $71, $107           # Px
        fma     $85, $70, $72, $108           # Py
        fma     $86, $70, $73, $109           # Pz
        SH_ADDI $74, $66, SH_PX
        stqx    $84, $74, $67
        SH_ADDI $74, $66, SH_PY
        stqx    $85, $74, $67
        SH_ADDI $74, $66, SH_PZ
        stqx    $86, $74, $67
        ceqi    $87, $120, 0
        ceqi    $88, $120, 1
        selb    $89, $84, $86, $88            # u: k0 -> y, k1 -> z, k2 -> x
        selb    $89, $89, $85, $87
        selb    $90, $85, $84, $88            # v: k0 -> z, k1 -> x, k2 -> y
        selb    $90, $90, $86, $87
        fm      $94, $121, $89                # beta = (b_nu u + b_nv v) + b_d
        fma     $94, $122, $90, $94
        fa      $94, $94, $123
        fm      $95, $124, $89                # gamma = (c_nu u + c_nv v) + c_d
        fma     $95, $125, $90, $95
        fa      $95, $95, $126
        # the normal n0 + beta (n1 - n0) + gamma (n2 - n0), turned to the eye
        .irp    C, 0, 16, 32
        lqd     $74, SH_NRM+\C($66)
        lqd     $75, SH_NRM+64+\C($66)
        lqd     $76, SH_NRM+128+\C($66)
        lqd     $77, SH_NRM+192+\C($66)
        SH_TRANSPOSE $74, $75, $76, $77, $80, $81, $82, $83, $84, $85, $86, $87
        stqd    $80, SH_SCRATCH+3*\C($66)    # vertex C/16: x, y, z columns
        stqd    $81, SH_SCRATCH+3*\C+16($66)
        stqd    $82, SH_SCRATCH+3*\C+32($66)
        .endr
        lqd     $74, SH_SCRATCH($66)          # n0
        lqd     $75, SH_SCRATCH+16($66)
        lqd     $76, SH_SCRATCH+32($66)
        lqd     $120, SH_SCRATCH+48($66)      # n1
        lqd     $80, SH_SCRATCH+64($66)
        lqd     $81, SH_SCRATCH+80($66)
        lqd     $82, SH_SCRATCH+96($66)       # n2
        lqd     $83, SH_SCRATCH+112($66)
        lqd     $84, SH_SCRATCH+128($66)
        fs      $85, $120, $74                # n1 - n0
        fs      $86, $80, $75
        fs      $87, $81, $76
        fs      $88, $82, $74                 # n2 - n0
        fs      $89, $83, $75
        fs      $90, $84, $76
        fma     $85, $85, $94, $74            # n0 + (n1 - n0) beta
        fma     $86, $86, $94, $75
        fma     $87, $87, $94, $76
        fma     $85, $88, $95, $85            # + (n2 - n0) gamma
        fma     $86, $89, $95, $86
        fma     $87, $90, $95, $87
        fm      $88, $85, $71                 # dot(N, d) > 0: negate N
        fma     $88, $86, $72, $88
        fma     $88, $87, $73, $88
        fcgt    $88, $88, ZERO
        ilhu    $89, 0x8000
        and     $88, $88, $89
        xor     $85, $85, $88
        xor     $86, $86, $88
        xor     $87, $87, $88
        hbrr    .Lsh_group_br, .Lsh_group
        SH_ADDI $74, $66, SH_NX
        stqx    $85, $74, $67
        SH_ADDI $74, $66, SH_NY
        stqx    $86, $74, $67
        SH_ADDI $74, $66, SH_NZ
        stqx    $87, $74, $67
.Lsh_group_next:
        ai      $67, $67, 16
        ceqi    $74, $67, 256
.Lsh_group_br:
        brz     $74, .Lsh_group
        br      .Lsh_colour
.Lsh_group_empty:                             # no hit: no material
        SH_ADDI $74, $66, SH_MAT
        stqx    $78, $74, $67
        br      .Lsh_group_next

        # ---- 2. the colour block: wait for its previous put, clear to black
.Lsh_colour:
        brsl    $127, shadow_rays             # --shade shadows: SH_VIS (modules/shadow.s)
        lqd     $70, SH_STATS+SHS_PACKETS($66)
        andi    $114, $70, 1                  # which block
        shli    $115, $114, 8
        SH_ADDI $115, $115, SH_OUT
        a       $115, $115, $66               # its address
        ai      $116, $114, 6                 # its tag
        il      $71, 1
        shl     $71, $71, $116
        wrch    $MFC_WrTagMask, $71
        il      $71, 2
        wrch    $MFC_WrTagUpdate, $71
        rdch    $71, $MFC_RdTagStat
        ila     $90, sh_const
        lqd     $71, 192($90)
        il      $72, 0
1:      stqx    $71, $115, $72
        ai      $72, $72, 16
        ceqi    $73, $72, 256
        brz     $73, 1b

        # ---- 3. one pass per material still referenced
        SH_ADDI $68, $66, SH_MAT
        il      $107, 0                       # packets before this one are all done
.Lsh_pass:
        ori     $67, $107, 0
1:      ceqi    $73, $67, 256
        brnz    $73, .Lsh_done
        lqx     $70, $68, $67
        ceqi    $71, $70, -1
        gb      $72, $71
        ceqi    $73, $72, 15
        ai      $67, $67, 16
        brnz    $73, 1b
        ai      $67, $67, -16
        ori     $107, $67, 0
        xori    $72, $72, 15                  # lanes with a material: the first
        clz     $72, $72
        ai      $72, $72, -28
        shli    $72, $72, 2
        rotqby  $110, $70, $72                # the material, preferred slot
        SH_COUNT SHS_PASSES, $74
        # material cache
        and     $71, $110, $105
        shli    $72, $71, 4
        SH_ADDI $72, $72, SH_MTAGS
        a       $72, $72, $66
        shli    $73, $71, 5
        SH_ADDI $73, $73, SH_MDATA
        a       $73, $73, $66
        lqd     $74, 0($72)
        ceq     $75, $74, $110
        SH_COUNT SHS_MLOOK, $76
        brnz    $75, 3f
        shli    $74, $110, 5
        a       $74, $74, $101
        il      $75, 32
        SH_GET  $73, $74, $75, $76
        stqd    $110, 0($72)
        SH_COUNT SHS_MMISS, $76
3:      lqd     $74, 0($73)                   # diffuse r, g, b
        shufb   $121, $74, $74, $91
        shufb   $122, $74, $74, $92
        shufb   $123, $74, $74, $93
        shufb   $110, $110, $110, $91         # the material in every lane
        ila     $90, sh_const
        lqd     $124, 112($90)                # ambient
        lqd     $125, 176($90)                # 1.0
        lqd     $126, 144($90)                # 0.5
        lqd     $127, 160($90)                # 1.5
        lqd     $106, 128($90)                # 255
        il      $67, 0
.Lsh_packet:
        lqx     $70, $68, $67
        ceq     $69, $70, $110                # this shader's rays
        gb      $71, $69
        brz     $71, .Lsh_packet_next
        SH_ADDI $71, $66, SH_NX
        lqx     $72, $71, $67
        SH_ADDI $71, $66, SH_NY
        lqx     $73, $71, $67
        SH_ADDI $71, $66, SH_NZ
        lqx     $74, $71, $67
        SH_ADDI $71, $66, SH_PX
        lqx     $75, $71, $67
        SH_ADDI $71, $66, SH_PY
        lqx     $76, $71, $67
        SH_ADDI $71, $66, SH_PZ
        lqx     $77, $71, $67
        fm      $78, $72, $72                 # dot(N, N)
        fma     $78, $73, $73, $78
        fma     $78, $74, $74, $78
        il      $79, 0                        # irradiance r, g, b
        il      $80, 0
        il      $81, 0
        SH_ADDI $82, $66, SH_LIGHTS
        SH_ADDI $83, $66, SH_VIS
        ori     $84, $103, 0                  # lights left
        brz     $84, 5f
4:      lqd     $85, 0($82)
        lqd     $86, 16($82)
        lqd     $87, 32($82)
        fs      $85, $85, $75                 # L = light - P
        fs      $86, $86, $76
        fs      $87, $87, $77
        fm      $88, $72, $85                 # c = dot(N, L)
        fma     $88, $73, $86, $88
        fma     $88, $74, $87, $88
        fm      $89, $85, $85                 # dot(L, L)
        fma     $89, $86, $86, $89
        fma     $89, $87, $87, $89
        fcgt    $94, $88, ZERO                # lit: facing the light
        lqx     $95, $83, $67                 # and not occluded
        and     $94, $94, $95
        fm      $89, $78, $89                 # 1 / sqrt(dot(N, N) dot(L, L)): estimate,
        frsqest $95, $89                      # interpolation, one Newton step
        fi      $95, $89, $95
        fm      $96, $89, $95
        fm      $96, $96, $95
        fnms    $96, $96, $126, $127          # 1.5 - 0.5 x y^2
        fm      $95, $95, $96
        fm      $88, $88, $95                 # cosine, at most 1, 0 when unlit
        fcgt    $96, $88, $125
        selb    $88, $88, $125, $96
        and     $88, $88, $94
        lqd     $85, 48($82)
        lqd     $86, 64($82)
        lqd     $87, 80($82)
        fma     $79, $88, $85, $79
        fma     $80, $88, $86, $80
        fma     $81, $88, $87, $81
        ai      $82, $82, 96
        ai      $83, $83, 256
        ai      $84, $84, -1
        brnz    $84, 4b
5:      hbrr    .Lsh_packet_br, .Lsh_packet
        fa      $79, $79, $124                # kd * (ambient + irradiance), clamped,
        fa      $80, $80, $124                # to 8 bits: (c 255 + 0.5) truncated
        fa      $81, $81, $124
        fm      $79, $79, $121
        fm      $80, $80, $122
        fm      $81, $81, $123
        .irp    R, $79, $80, $81
        fcgt    $96, \R, $125
        selb    \R, \R, $125, $96
        fma     \R, \R, $106, $126
        cfltu   \R, \R, 0
        .endr
        shli    $79, $79, 24
        shli    $80, $80, 16
        shli    $81, $81, 8
        or      $79, $79, $80
        or      $79, $79, $81
        ori     $79, $79, 0xff
        lqx     $80, $115, $67
        selb    $80, $80, $79, $69
        stqx    $80, $115, $67
        il      $71, -1                       # these rays are shaded
        selb    $70, $70, $71, $69
        stqx    $70, $68, $67
.Lsh_packet_next:
        ai      $67, $67, 16
        ceqi    $71, $67, 256
.Lsh_packet_br:
        brz     $71, .Lsh_packet
        br      .Lsh_pass

        # ---- 4. put the block to ea_colour + packet * 256
.Lsh_done:
        shli    $70, $97, 8
        a       $70, $70, $102
        il      $71, 256
        wrch    $MFC_LSA, $115
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $70
        wrch    $MFC_Size, $71
        wrch    $MFC_TagID, $116
        il      $71, 0x20
        wrch    $MFC_Cmd, $71
        SH_COUNT SHS_PACKETS, $74
        bi      $0

# a vertex cache miss: vertex $81 into line $84, tag $83; back to $88
sh_vertex_miss:
        shli    $85, $81, 6
        a       $85, $85, $100
        il      $86, 64
        SH_GET  $84, $85, $86, $87
        stqd    $81, 0($83)
        SH_COUNT SHS_VMISS, $87
        bi      $88

# a triangle record the traversal's cache does not hold: record $80 into $82; back to $88
sh_tri_miss:
        SH_COUNT SHS_TMISS, $84
        shli    $81, $80, 6
        a       $81, $81, EATRIS
        il      $83, 64
        SH_GET  $82, $81, $83, $84
        bi      $88
shade_end:
