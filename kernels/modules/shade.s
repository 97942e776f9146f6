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
#    splatted to the 4 lanes; otherwise per lane, the lanes' rows transposed into columns.
#    Vertices go through a direct-mapped cache of 64-byte records
#    (ShadingBlock.vertex_cache_log2 entries). Per ray the hit point o + t d, its
#    barycentrics (the projection of the record, as the hit test computed them), the
#    interpolated normal facing the eye and the material are stored structure-of-arrays.
#    Three paths, the hot ones scheduled `.sched` blocks: same-triangle packets found in
#    the caches, two per step; mixed packets found in the caches; anything else (a cache
#    miss, no hit) lane by lane, its vertex misses fetched without waiting into staging
#    slots and landed together once its lanes are looked up (sh_vertex_miss,
#    SH_LAND: one wait per packet of 4 rays, not one per miss; the triangle records
#    past the traversal's cache likewise, one wait before they are read). They compute the
#    same values and counts. A packet none of whose rays hit has no i-set (its materials
#    -1, the counters as they are).
# 2. Multi-pass shading: the first material still referenced in the i-set is looked up in
#    the direct-mapped material cache, its diffuse shader (kd * (ambient + irradiance), to
#    8 bits) runs over all 16 intersection packets under the mask of its rays, and then
#    clears their references; until none is left (the paper's 1-2 passes per packet). The
#    irradiance, dot(N, L) / (|N| |L|) clamped, times the light's colour, summed over the
#    lights (SH_VIS: per light, the rays' visibility masks), is computed in the same block
#    as the colour: the first pass runs it once per light, adding to the sums (stored),
#    the last light's run shading; a later pass runs it with a black light (adding exactly
#    0), shading from the stored sums. The pass that leaves no material ends the packet.
#
# The shading area (SH_AREA_BYTES of local store, at the address the host puts in params
# beside the shading block's, above everything the kernel carves) is set up on the first
# call: the block is fetched, the lights splatted, the caches' tags cleared. Its counters
# (SH_STATS, one per quadword, word 0) are read by the host from local store, as the PPE
# reads an SPE's memory-mapped local store.

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
        .set SH_RUN, 176                # over a run of the shading block: the next light,
                                        # the lights left, the material; the colour
                                        # block's EA, tag, the material cache's EA, index
                                        # mask (64)
        .set SH_VMASK, 240              # the vertex index mask in every lane
        .set SH_BLOCK, 256              # the shading block (SHADING_BLOCK_BYTES)
        .set SH_LIGHTS, 640             # per light: px, py, pz, r, g, b splats (96 bytes)
        .set SH_SCRATCH, 1408           # the normals' columns (144 bytes), the same flag
        .set SH_SAVE, SH_SCRATCH+160    # the fast path's registers over the slow path (80)
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
        .set SH_IRR_R, SH_SCRATCH       # irradiance r, g, b of the i-set (after the i-set
        .set SH_IRR_G, SH_STAGE         # is built, over its scratch: 16 vectors each)
        .set SH_IRR_B, SH_NRM
        .if     SH_NRM != SH_STAGE + 256
        .error  "the slow path reads the records and normals from one base"
        .endif
        .if     SH_IRR_G != SH_IRR_R + 256 || SH_IRR_B != SH_IRR_R + 512
        .error  "the irradiance sums are read from one base"
        .endif
        .set SH_OUT, 3968               # two colour blocks, alternating
        .set SH_VIS, 4480               # per light: visibility masks (256 bytes)
        .set SH_VTAGS, 6528             # vertex cache tags (up to 256 x 16)
        .set SH_VDATA, 10624            # vertex cache lines (up to 256 x 64)
        .set SH_MTAGS, 27008            # material cache tags (up to 256 x 16)
        .set SH_MDATA, 31104            # material cache lines (up to 256 x 32)
        .set SH_DCOUNT, 39296           # the vertices in flight (sh_vertex_miss): bytes of
        .set SH_DEFER, 39312            # their copies (source, destination; line: up to
        .set SH_VSTAGE, 39808           # 12, a group's lookups) and staging slots (64 bytes)
        .set SH_AREA_BYTES, 40576
        .if     SH_DEFER + 12 * 32 > SH_VSTAGE || SH_VSTAGE + 12 * 64 != SH_AREA_BYTES
        .error  "the vertices in flight do not fit"
        .endif
        .set SH_TAG, 5
        .set CTX_RAY_T, 1536
        .set CTX_RAY_ID, 1792                  # fetches; colour output on 6 and 7

# rt = ra + an area offset (beyond ai's 10 bits, up to 18; $96 is the scratch)
        .macro  SH_ADDI rt, ra, off
        ila     $96, \off
        a       \rt, \ra, $96
        .endm

# wait for the fetches on tag SH_TAG (tmp: a scratch register)
        .macro  SH_WAIT tmp
        il      \tmp, 1 << SH_TAG
        wrch    $MFC_WrTagMask, \tmp
        il      \tmp, 2
        wrch    $MFC_WrTagUpdate, \tmp
        rdch    \tmp, $MFC_RdTagStat
        .endm

# queue a get LS <- EA of SIZE bytes (an immediate) on tag SH_TAG, not waited for
# (registers: ls, ea, scratch; the scratch may be ea)
        .macro  SH_QUEUE ls, ea, size, tmp
        wrch    $MFC_LSA, \ls
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, \ea
        il      \tmp, \size
        wrch    $MFC_Size, \tmp
        il      \tmp, SH_TAG
        wrch    $MFC_TagID, \tmp
        il      \tmp, 0x40
        wrch    $MFC_Cmd, \tmp
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
        SH_WAIT \tmp
        .endm

# $71 quadwords of VALUE from the area's OFF on ($72: scratch)
        .macro  SH_FILL value, off
        SH_ADDI $72, $66, \off
1:      stqd    \value, 0($72)
        ai      $72, $72, 16
        ai      $71, $71, -1
        brnz    $71, 1b
        .endm

# counter += 1 (a quadword of SH_STATS; $66 = area)
        .macro  SH_COUNT which, tmp
        lqd     \tmp, SH_STATS+\which($66)
        ai      \tmp, \tmp, 1
        stqd    \tmp, SH_STATS+\which($66)
        .endm

# vertex I of lane LANE: the normal of vertex word I of $80 (the record's spare quad) to
# SH_NRM + LANE*64 + I*16, through the vertex cache (TAG, LINE: its tag's and line's
# addresses in the preferred word); a miss calls sh_vertex_miss ($114) without a taken
# branch on the hit path. The normal is loaded to $90; STORE (not -) stores vertex
# STORE's, the previous one's, before this lookup's call (which may change $90)
        .macro  SH_VERTEX lane, i, tag, line, store
        lqd     $85, 0(\tag)
        rotqbyi $81, $80, 4*\i
        ori     $83, \tag, 0
        ori     $84, \line, 0
        ila     $88, 1f
        ila     $89, SH_NRM+\lane*64+\i*16
        .ifnc   \store, -
        stqd    $90, SH_NRM+\lane*64+\store*16($66)
        .endif
        ceq     $86, $85, $81
        biz     $86, $114
1:      lqd     $90, 16($84)
        .endm

# (in the slow path, once a group's lanes are looked up) the vertices in flight: one
# wait, then each copy (uses $81, $85-$90, $94). Inline, not a call: an unhinted call and
# return cost 37 cycles, which the beetle paid 41,000 times a frame.
        .macro  SH_LAND
        SH_ADDI $87, $66, SH_DCOUNT
        lqd     $86, 0($87)
        brz     $86, 2f
        stqd    ZERO, 0($87)
        SH_WAIT $85
        SH_ADDI $94, $66, SH_DEFER
        a       $86, $86, $94                 # the end
        .sched  pool=81,85,87-90 scratch=66-127
1:
        lqd     %r0, 0($94)                   # the source, the lane, the tag, the vertex
        lqd     %line, 16($94)
        lqd     %nrm, 16(%r0)                 # the normal (all the lines are read for)
        rotqbyi %lane, %r0, 4
        rotqbyi %tag, %r0, 8
        rotqbyi %v, %r0, 12
        stqd    %nrm, 16(%line)
        stqd    %nrm, 0(%lane)
        stqd    %v, 0(%tag)                   # landed
        ai      $94, $94, 32
        ceq     %end, $94, $86
        hbrr    3f, 1b
3:
        brz     %end, 1b
        .endsched
2:
        .endm

# lane LANE of the intersection packet in $70 (ids): its record to SH_STAGE + LANE*64
# (nothing for a miss); a record the traversal's triangle cache does not hold is fetched
# by sh_tri_miss ($106), not waited for (SH_WAIT before the records are read)
        .macro  SH_FETCH lane
        rotqbyi $80, $70, 4*\lane
        ceqi    $81, $80, -1
        brnz    $81, 3f
        SH_ADDI $82, $66, SH_STAGE+\lane*64
        ila     $88, 3f
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
3:
        .endm

# lane LANE's vertex normals to SH_NRM + LANE*64 (nothing for a miss), its record staged
# (uses $79, $95, $101-$103, $105 besides SH_VERTEX's)
        .macro  SH_NORMALS lane
        rotqbyi $80, $70, 4*\lane
        ceqi    $81, $80, -1
        brnz    $81, 3f
        lqd     $80, SH_STAGE+\lane*64+48($66)
        and     $82, $80, $121                # the vertices' indices (words 0-2), their
        shufb   $83, $115, $115, $91          # tags' and lines' addresses ($115 tags,
        shufb   $84, $116, $116, $91          # $116 lines: splatted; $121 the index
        shli    $79, $82, 4                   # mask, splatted)
        shli    $95, $82, 6
        a       $79, $79, $83
        a       $95, $95, $84
        rotqbyi $101, $79, 4
        rotqbyi $102, $95, 4
        rotqbyi $103, $79, 8
        rotqbyi $105, $95, 8
        SH_VERTEX \lane, 0, $79, $95, -
        SH_VERTEX \lane, 1, $101, $102, 0
        SH_VERTEX \lane, 2, $103, $105, 1
        stqd    $90, SH_NRM+\lane*64+32($66)
3:
        .endm

# (in a .sched block) the hit point o + t d of the rays at %rp, stored at %gp, its
# barycentrics from the columns K (the projection axis), B and C (u, v, constant terms),
# and the normal from the columns n0, n1 - n0, n2 - n0, turned to the eye ($122: sign bits)
        .macro  SH_GROUP_COLUMNS k, bu, bv, bd, cu, cv, cd, n0x, n0y, n0z, d1x, d1y, d1z, d2x, d2y, d2z
        lqd     %t, CTX_RAY_T(%rp)
        lqd     %dx, 0(%rp)
        lqd     %dy, 256(%rp)
        lqd     %dz, 512(%rp)
        fma     %px, %t, %dx, $107            # the hit point
        fma     %py, %t, %dy, $108
        fma     %pz, %t, %dz, $109
      ~ stqd    %px, SH_PX(%gp)
      ~ stqd    %py, SH_PY(%gp)
      ~ stqd    %pz, SH_PZ(%gp)
        ceqi    %k0, \k, 0
        ceqi    %k1, \k, 1
        selb    %u1, %px, %pz, %k1            # u: k0 -> y, k1 -> z, k2 -> x
        selb    %u, %u1, %py, %k0
        selb    %v1, %py, %px, %k1            # v: k0 -> z, k1 -> x, k2 -> y
        selb    %v, %v1, %pz, %k0
        fm      %b1, \bu, %u                 # beta = (b_nu u + b_nv v) + b_d
        fma     %b2, \bv, %v, %b1
        fa      %beta, %b2, \bd
        fm      %g1, \cu, %u                 # gamma = (c_nu u + c_nv v) + c_d
        fma     %g2, \cv, %v, %g1
        fa      %gamma, %g2, \cd
        fma     %nx1, \d1x, %beta, \n0x       # n0 + (n1 - n0) beta + (n2 - n0) gamma
        fma     %ny1, \d1y, %beta, \n0y
        fma     %nz1, \d1z, %beta, \n0z
        fma     %nx, \d2x, %gamma, %nx1
        fma     %ny, \d2y, %gamma, %ny1
        fma     %nz, \d2z, %gamma, %nz1
        fm      %e1, %nx, %dx                 # dot(N, d) > 0: negate N
        fma     %e2, %ny, %dy, %e1
        fma     %e, %nz, %dz, %e2
        fcgt    %f1, %e, ZERO
        and     %f, %f1, $122
        xor     %nxo, %nx, %f
        xor     %nyo, %ny, %f
        xor     %nzo, %nz, %f
      ~ stqd    %nxo, SH_NX(%gp)
      ~ stqd    %nyo, SH_NY(%gp)
      ~ stqd    %nzo, SH_NZ(%gp)
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
        .float  1.5, 1.5, 1.5, 1.5                                 # +160 (unused)
        .float  1.0, 1.0, 1.0, 1.0                                 # +176
        .long   0x000000ff, 0x000000ff, 0x000000ff, 0x000000ff     # +192 a miss: black
        .long   0x0c0d0e0f, 0x0c0d0e0f, 0x0c0d0e0f, 0x0c0d0e0f     # +208 splat word 3
        .long   0x80000000, 0x80000000, 0x80000000, 0x80000000     # +224 sign bits
        .long   1, 1, 1, 0                  # +240 a fast group: groups, same, tri lookups
        .long   0x10111213, 0x00010203, 0x10111213, 0x00010203     # +256 list element (b, a)
        .long   0x001080c0, 0x041480c0, 0x081880c0, 0x0c1c80c0     # +272 r, g top bytes, 0xff
        .long   0x00011003, 0x04051407, 0x0809180b, 0x0c0d1c0f     # +288 b top byte
        .long   0x0004080c, 0x1014181c, 0x80808080, 0x80808080     # +304 top bytes of a, b
        .long   0x80808080, 0x80808080, 0x0004080c, 0x1014181c     # +320 ... to bytes 8-15
        .long   0x00010203, 0x14151617, 0x18191a1b, 0x1c1d1e1f     # +336 a's word 0, b's 1-3
sh_zero:                                      # no irradiance, a black light (768 bytes)
        .space  768

        .align  3
shade_packet:
        .sched  pool=73-89,94-96,98,100-106,110-114,116-118 scratch=66-127
        ila     $70, params
        ila     $90, sh_const
        lqd     $71, PARAM_SHADING_QUAD($70)
        lqd     $72, PARAM_ORIGIN($70)
        lqd     $91, 64($90)
        lqd     $92, 80($90)
        lqd     $93, 96($90)
        lqd     $119, 32($90)
        lqd     $120, 208($90)                # splat word 3
        lqd     $122, 224($90)                # sign bits
        ori     $99, $68, 0                   # the rays
        ori     $97, $69, 0                   # the packet number
        rotqbyi $71, $71, PARAM_SHADING_ROT   # shading block EA, area
        rotqbyi $66, $71, 4                   # the shading area
        lqd     $67, SH_FLAG($66)
        lqd     $121, SH_VMASK($66)           # the vertex index mask in every lane
        ilhu    $68, 0x5348
        iohl    $68, 0x4144                   # "SHAD"
        shufb   $107, $72, $72, $91           # origin x, y, z splats
        shufb   $108, $72, $72, $92
        shufb   $109, $72, $72, $93
        ila     %vt, SH_VTAGS
        a       $115, $66, %vt
        ila     %vd, SH_VDATA+16
        a       $123, $66, %vd                # the lines' normals
        il      $124, 0                       # the fast groups' counters (sh_const+240)
        lqd     %id0, CTX_RAY_ID+0($99)
        lqd     %id1, CTX_RAY_ID+16($99)
        lqd     %id2, CTX_RAY_ID+32($99)
        lqd     %id3, CTX_RAY_ID+48($99)
        lqd     %id4, CTX_RAY_ID+64($99)
        lqd     %id5, CTX_RAY_ID+80($99)
        lqd     %id6, CTX_RAY_ID+96($99)
        lqd     %id7, CTX_RAY_ID+112($99)
        lqd     %id8, CTX_RAY_ID+128($99)
        lqd     %id9, CTX_RAY_ID+144($99)
        lqd     %id10, CTX_RAY_ID+160($99)
        lqd     %id11, CTX_RAY_ID+176($99)
        lqd     %id12, CTX_RAY_ID+192($99)
        lqd     %id13, CTX_RAY_ID+208($99)
        lqd     %id14, CTX_RAY_ID+224($99)
        lqd     %id15, CTX_RAY_ID+240($99)
        and     %and1, %id0, %id1
        and     %and2, %id2, %id3
        and     %and3, %id4, %id5
        and     %and4, %id6, %id7
        and     %and5, %id8, %id9
        and     %and6, %id10, %id11
        and     %and7, %id12, %id13
        and     %and8, %id14, %id15
        and     %and9, %and1, %and2
        and     %and10, %and3, %and4
        and     %and11, %and5, %and6
        and     %and12, %and7, %and8
        and     %and13, %and9, %and10
        and     %and14, %and11, %and12
        and     %and15, %and13, %and14
        ceqi    %ne, %and15, -1
        gb      %nb, %ne
        ceqi    $117, %nb, 15                 # no ray of the packet hit
        ceq     $69, $67, $68
        brz     $69, .Lsh_first               # the first call: set up (out of line)
        .endsched
.Lsh_ready:
        # ---- 1. the i-set (none when no ray hit: every material -1)
        il      $67, 0                        # intersection packet * 16
        brnz    $117, .Lsh_empty
        .align  7                             # (the loop's head at a fetch line's start)

        # The fast path, two groups a step, for a group whose 4 rays hit one triangle found
        # in the triangle cache with its 3 vertices in the vertex cache (94.9% in the
        # room): every lookup is made speculatively (masked indices keep the loads in the
        # caches) and the group shaded from splats; a branch at the end sends a step with
        # any other group to the slow path, which does that group (and its stores) again,
        # lane by lane.
        .sched  pool=68-90,94-96,98,100-106,110-114,116-118,125-127 scratch=66-127
.Lsh_group:
        a       %rp, $99, $67
        a       %gp, $66, $67
        .irp    H, 0, 16
        lqd     %ids\H, CTX_RAY_ID+\H(%rp)
        ceqi    %miss\H, %ids\H, -1
        shufb   %s0\H, %ids\H, %ids\H, $91
        ceq     %same\H, %ids\H, %s0\H
        gb      %sameb\H, %same\H
        ceqi    %ok0\H, %sameb\H, 15
        andc    %ok1\H, %ok0\H, %miss\H
        and     %ti\H, %ids\H, TMASK
        shli    %to\H, %ti\H, 4
        lqx     %tag\H, TTAGS, %to\H
        shli    %tl\H, %ti\H, 6
        a       %line\H, %tl\H, TDATA
        ceq     %th\H, %tag\H, %ids\H
        and     %ok2\H, %ok1\H, %th\H
        lqd     %q3\H, 48(%line\H)                # vertex indices, material
        and     %vi\H, %q3\H, $121
        shli    %vo0\H, %vi\H, 4
        shli    %vl0\H, %vi\H, 6
        rotqbyi %vo1\H, %vo0\H, 4
        rotqbyi %vo2\H, %vo0\H, 8
        rotqbyi %vl1\H, %vl0\H, 4
        rotqbyi %vl2\H, %vl0\H, 8
        lqx     %vt0\H, $115, %vo0\H
        lqx     %vt1\H, $115, %vo1\H
        lqx     %vt2\H, $115, %vo2\H
        rotqbyi %q3b\H, %q3\H, 4
        rotqbyi %q3c\H, %q3\H, 8
        ceq     %h0\H, %vt0\H, %q3\H
        ceq     %h1\H, %vt1\H, %q3b\H
        ceq     %h2\H, %vt2\H, %q3c\H
        and     %h01\H, %h0\H, %h1\H
        and     %h012\H, %h01\H, %h2\H
        and     %ok\H, %ok2\H, %h012\H
        lqx     %n0\H, $123, %vl0\H
        lqx     %n1\H, $123, %vl1\H
        lqx     %n2\H, $123, %vl2\H
        lqd     %q0\H, 0(%line\H)
        lqd     %q1\H, 16(%line\H)
        lqd     %q2\H, 32(%line\H)
        lqd     %t\H, CTX_RAY_T+\H(%rp)
        lqd     %dx\H, 0+\H(%rp)
        lqd     %dy\H, 256+\H(%rp)
        lqd     %dz\H, 512+\H(%rp)
        fma     %px\H, %t\H, %dx\H, $107            # the hit point
        fma     %py\H, %t\H, %dy\H, $108
        fma     %pz\H, %t\H, %dz\H, $109
      ~ stqd    %px\H, SH_PX+\H(%gp)
      ~ stqd    %py\H, SH_PY+\H(%gp)
      ~ stqd    %pz\H, SH_PZ+\H(%gp)
        shufb   %mat\H, %q3\H, %q3\H, $120
      ~ stqd    %mat\H, SH_MAT+\H(%gp)
        shufb   %k\H, %q0\H, %q0\H, $120
        ceqi    %k0\H, %k\H, 0
        ceqi    %k1\H, %k\H, 1
        selb    %u1\H, %px\H, %pz\H, %k1\H            # u: k0 -> y, k1 -> z, k2 -> x
        selb    %u\H, %u1\H, %py\H, %k0\H
        selb    %v1\H, %py\H, %px\H, %k1\H            # v: k0 -> z, k1 -> x, k2 -> y
        selb    %v\H, %v1\H, %pz\H, %k0\H
        shufb   %bnu\H, %q1\H, %q1\H, $91
        shufb   %bnv\H, %q1\H, %q1\H, $92
        shufb   %bd\H, %q1\H, %q1\H, $93
        shufb   %cnu\H, %q2\H, %q2\H, $91
        shufb   %cnv\H, %q2\H, %q2\H, $92
        shufb   %cd\H, %q2\H, %q2\H, $93
        fm      %b1\H, %bnu\H, %u\H                 # beta = (b_nu u + b_nv v) + b_d
        fma     %b2\H, %bnv\H, %v\H, %b1\H
        fa      %beta\H, %b2\H, %bd\H
        fm      %g1\H, %cnu\H, %u\H                 # gamma = (c_nu u + c_nv v) + c_d
        fma     %g2\H, %cnv\H, %v\H, %g1\H
        fa      %gamma\H, %g2\H, %cd\H
        fs      %d1\H, %n1\H, %n0\H                 # n1 - n0, n2 - n0
        fs      %d2\H, %n2\H, %n0\H
        shufb   %n0x\H, %n0\H, %n0\H, $91
        shufb   %n0y\H, %n0\H, %n0\H, $92
        shufb   %n0z\H, %n0\H, %n0\H, $93
        shufb   %d1x\H, %d1\H, %d1\H, $91
        shufb   %d1y\H, %d1\H, %d1\H, $92
        shufb   %d1z\H, %d1\H, %d1\H, $93
        shufb   %d2x\H, %d2\H, %d2\H, $91
        shufb   %d2y\H, %d2\H, %d2\H, $92
        shufb   %d2z\H, %d2\H, %d2\H, $93
        fma     %nx1\H, %d1x\H, %beta\H, %n0x\H       # n0 + (n1 - n0) beta + (n2 - n0) gamma
        fma     %ny1\H, %d1y\H, %beta\H, %n0y\H
        fma     %nz1\H, %d1z\H, %beta\H, %n0z\H
        fma     %nx\H, %d2x\H, %gamma\H, %nx1\H
        fma     %ny\H, %d2y\H, %gamma\H, %ny1\H
        fma     %nz\H, %d2z\H, %gamma\H, %nz1\H
        fm      %e1\H, %nx\H, %dx\H                 # dot(N, d) > 0: negate N
        fma     %e2\H, %ny\H, %dy\H, %e1\H
        fma     %e\H, %nz\H, %dz\H, %e2\H
        fcgt    %f1\H, %e\H, ZERO
        and     %f\H, %f1\H, $122
        xor     %nxo\H, %nx\H, %f\H
        xor     %nyo\H, %ny\H, %f\H
        xor     %nzo\H, %nz\H, %f\H
      ~ stqd    %nxo\H, SH_NX+\H(%gp)
      ~ stqd    %nyo\H, SH_NY+\H(%gp)
      ~ stqd    %nzo\H, SH_NZ+\H(%gp)
        .endr
        shufb   %okp, %ok0, %ok16, $119
      ~ stqd    %okp, SH_SCRATCH+144($66)     # which of the two groups are done
        lqa     %cinc, sh_const+240
        shufb   %okv0, %ok0, %ok0, $91
        shufb   %okv16, %ok16, %ok16, $91
        and     %inc0, %cinc, %okv0
        and     %inc16, %cinc, %okv16
        a       %inc, %inc0, %inc16
        a       $124, $124, %inc
        and     %okab, %ok0, %ok16
        ai      $67, $67, 32
        ceqi    %end, $67, 256
        ila     %loop, .Lsh_group
        ila     %exit, .Lsh_iset_done
        selb    %to, %loop, %exit, %end       # (a hinted exit: no miss at the end)
        hbr     .Lsh_group_br, %to
        brz     %okab, .Lsh_slow
.Lsh_group_br:
        bi      %to
        .endsched
        # (the slow path: out of line, after the end)

        # the fast groups' counters (groups, same, triangle lookups) to SH_STATS
.Lsh_iset_done:
        .sched  pool=69,76-81,90,94-96,98-100,104,107-109,111-113,117-120 scratch=66-127
        lqd     $70, SH_BLOCK($66)            # materials, colour, lights
        lqd     $71, SH_BLOCK+SHB_MODE($66)
        lqd     %cg, SH_STATS+SHS_GROUPS($66)
        lqd     %cs, SH_STATS+SHS_SAME($66)
        lqd     %ct, SH_STATS+SHS_TLOOK($66)
        rotqbyi %is, $124, 4
        rotqbyi %it, $124, 8
        a       %cg1, %cg, $124
        a       %cs1, %cs, %is
        a       %ct1, %ct, %it
        stqd    %cg1, SH_STATS+SHS_GROUPS($66)
        stqd    %cs1, SH_STATS+SHS_SAME($66)
        stqd    %ct1, SH_STATS+SHS_TLOOK($66)
        rotqbyi $101, $70, 4
        rotqbyi $102, $70, 8
        rotqbyi $103, $70, 12
        rotqbyi %ml, $71, 12
        il      %one, 1
        shl     %me, %one, %ml
        ai      $105, %me, -1                 # material cache index mask
        hbrr    .Lsh_shadows, shadow_rays
        # Here the hit points are in SH_PX, SH_PY, SH_PZ (and the materials in SH_MAT, -1
        # for no hit): the place for shadow rays to fill SH_VIS (per light, the rays'
        # visibility masks), which the irradiance below reads. Only $66, $97, $101..$103
        # and $105 need to survive up to here; the rest is set again below.
.Lsh_shadows:
        brsl    $127, shadow_rays             # --shade shadows: SH_VIS (modules/shadow.s)
        .endsched

        # ---- 2. the colour block: wait for its previous put, clear to black; what the
        # passes and the put need over the runs (their registers are the block's pool)
        .sched  pool=69,76-81,90,94-96,98-100,104,107-109,111-113,117-120 scratch=66-127
        lqd     %pk, SH_STATS+SHS_PACKETS($66)
        andi    $114, %pk, 1                  # which block
        shli    %bo, $114, 8
        ila     %ob, SH_OUT
        a       %b1, %bo, %ob
        a       $115, %b1, $66                # its address
        ai      $116, $114, 6                 # its tag
        il      %one, 1
        shl     %mask, %one, $116
        il      %two, 2
        lqa     %black, sh_const+192
        shli    %ea0, $97, 8
        a       %ea, %ea0, $102
        lqa     %plo, sh_const
        lqa     %pfh, sh_const+32
        shufb   %w0, %ea, $116, %plo
        shufb   %w1, $101, $105, %plo
        shufb   %w, %w0, %w1, %pfh
        stqd    %w, SH_RUN+48($66)            # EA, tag, material cache EA, index mask
        ila     %o1, SH_MAT
        a       $68, $66, %o1
        ila     %o2, SH_LIGHTS
        a       $82, $66, %o2                 # the next light,
        ila     %o3, SH_VIS
        a       $83, $66, %o3                 # its visibility,
        shufb   $84, $103, $103, $91          # the first pass's lights left (every lane)
        ila     $85, sh_zero                  # the irradiance so far: none
        wrch    $MFC_WrTagMask, %mask
        wrch    $MFC_WrTagUpdate, %two
        rdch    %st, $MFC_RdTagStat
        .irp    Q, 0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 208, 224, 240
        stqd    %black, \Q($115)
        .endr
        .endsched

        # ---- 3. one pass per material still referenced, its rays' irradiance computed in
        # the same block as their colour (runs of .Lsh_shade_g): in the first pass one run
        # per light, each adding its light to the sums (stored for later passes), the last
        # one shading (the ones before shade a material no ray has); a later pass is one
        # run adding nothing (a black light), which shades from the stored sums.
        # The first ray (group by group, lane by lane) with a material left: per 4 groups
        # the top bytes of their "none" masks gathered (gbb), 64 bits (lane 0 of group 0
        # the highest) in %hi and %lo.
        .sched  pool=69-81,90,94-96,98-100,103-104,107-109,111-113,117-120 scratch=66-127
.Lsh_pass:
        lqa     %pa, sh_const+304
        lqa     %pb, sh_const+320
        .irp    Q, 0, 1, 2, 3
        lqd     %ma\Q, 64*\Q($68)
        lqd     %mb\Q, 64*\Q+16($68)
        lqd     %mc\Q, 64*\Q+32($68)
        lqd     %md\Q, 64*\Q+48($68)
        ceqi    %ea\Q, %ma\Q, -1
        ceqi    %eb\Q, %mb\Q, -1
        ceqi    %ec\Q, %mc\Q, -1
        ceqi    %ed\Q, %md\Q, -1
        shufb   %tab\Q, %ea\Q, %eb\Q, %pa
        shufb   %tcd\Q, %ec\Q, %ed\Q, %pb
        or      %t\Q, %tab\Q, %tcd\Q
        gbb     %g\Q, %t\Q
        .endr
        shli    %g0s, %g0, 16
        shli    %g2s, %g2, 16
        or      %hig, %g0s, %g1
        or      %log, %g2s, %g3
        xori    %hi, %hig, -1
        clz     %hiz, %hi
        xori    %lo, %log, -1
        clz     %loz, %lo
        ceqi    %hin, %hi, 0
        ai      %lo32, %loz, 32
        selb    %pos, %hiz, %lo32, %hin        # 64: none left
        ceqi    %none, %pos, 64
        andi    %pq, %pos, -4
        shli    %go, %pq, 2                   # its group * 16
        andi    %ln, %pos, 3
        shli    %lb, %ln, 2                   # its lane * 4
        lqx     %mq, $68, %go
        rotqby  $110, %mq, %lb                # the material, preferred slot
        brnz    %none, .Lsh_done              # none left: the packet is done
        .endsched
.Lsh_material:
        .sched  pool=69,76-81,90,94-96,98-100,104,107-109,111-113,117-120 scratch=66-127
        lqd     %run, SH_RUN+48($66)
        lqd     %cp, SH_STATS+SHS_PASSES($66)
        lqd     %cl, SH_STATS+SHS_MLOOK($66)
        rotqbyi $101, %run, 8                 # the material cache's EA, index mask
        rotqbyi %mmask, %run, 12
        ai      %cp1, %cp, 1
        ai      %cl1, %cl, 1
        stqd    %cp1, SH_STATS+SHS_PASSES($66)
        stqd    %cl1, SH_STATS+SHS_MLOOK($66)
        and     %mi, $110, %mmask             # material cache
        shli    %to, %mi, 4
        ila     %tb, SH_MTAGS
        a       %t1, %to, %tb
        a       $72, %t1, $66
        shli    %lo, %mi, 5
        ila     %lb, SH_MDATA
        a       %l1, %lo, %lb
        a       $73, %l1, $66
        lqd     %tag, 0($72)
        ceq     %hit, %tag, $110
        brz     %hit, .Lsh_mmiss
        .endsched
.Lsh_mhit:
        .sched  pool=69,76-81,90,94-96,98-100,104,107-109,111-113,117-120 scratch=66-127
        lqd     %kd, 0($73)                   # diffuse r, g, b
        lqa     $91, sh_const+64              # (the patterns are the block's pool)
        lqa     $92, sh_const+80
        lqa     $93, sh_const+96
        shufb   $121, %kd, %kd, $91
        shufb   $122, %kd, %kd, $92
        shufb   $123, %kd, %kd, $93
        shufb   $110, $110, $110, $91         # the material in every lane
        lqa     $124, sh_const+112            # ambient
        lqa     $125, sh_const+176            # 1.0
        lqa     $126, sh_const+144            # 0.5
        lqa     $106, sh_const+128            # 255
        lqa     $88, sh_const+272             # r, g to a colour word
        lqa     $89, sh_const+288             # b to it
        .endsched
.Lsh_run:
        .sched  pool=69,76-81,90,94-96,98-100,104,107-109,111-113,117-120 scratch=66-127
        cgti    %notlast, $84, 1              # not the last light: shades no ray
        il      %m2, -2
        selb    $87, $110, %m2, %notlast      # the material shaded
        ceqi    %black, $84, 0                # a later pass (or no light): a black light
        ila     %zero, sh_zero
        selb    %lp, $82, %zero, %black
        lqd     $70, 0(%lp)                   # the light's position, colour
        lqd     $71, 16(%lp)
        lqd     $72, 32(%lp)
        lqd     $73, 48(%lp)
        lqd     $74, 64(%lp)
        lqd     $75, 80(%lp)
        il      $86, -1                       # every ray shaded, so far
        il      $67, 0
        stqd    $82, SH_RUN($66)              # (registers of the block's pool)
        stqd    $84, SH_RUN+16($66)
        stqd    $110, SH_RUN+32($66)
        .endsched
        .sched  pool=69,76-82,84,90-105,107-114,116-120 scratch=66-127
.Lsh_shade_g:
        a       %gp, $66, $67
        a       %vp, $83, $67
        a       %pp, $85, $67
        a       %op, $115, $67
        il      %none, -1
        .irp    H, 0, 16, 32, 48
        lqd     %nx\H, SH_NX+\H(%gp)
        lqd     %ny\H, SH_NY+\H(%gp)
        lqd     %nz\H, SH_NZ+\H(%gp)
        lqd     %px\H, SH_PX+\H(%gp)
        lqd     %py\H, SH_PY+\H(%gp)
        lqd     %pz\H, SH_PZ+\H(%gp)
        lqd     %vis\H, \H(%vp)
        lqd     %ir\H, \H(%pp)                # the sums so far (r, g, b 256 bytes apart)
        lqd     %ig\H, 256+\H(%pp)
        lqd     %ib\H, 512+\H(%pp)
        fm      %nn1\H, %nx\H, %nx\H          # dot(N, N)
        fma     %nn2\H, %ny\H, %ny\H, %nn1\H
        fma     %nn\H, %nz\H, %nz\H, %nn2\H
        fs      %lx\H, $70, %px\H             # L = light - P
        fs      %ly\H, $71, %py\H
        fs      %lz\H, $72, %pz\H
        fm      %c1\H, %nx\H, %lx\H           # c = dot(N, L)
        fma     %c2\H, %ny\H, %ly\H, %c1\H
        fma     %c\H, %nz\H, %lz\H, %c2\H
        fm      %l1\H, %lx\H, %lx\H           # dot(L, L)
        fma     %l2\H, %ly\H, %ly\H, %l1\H
        fma     %ll\H, %lz\H, %lz\H, %l2\H
        fcgt    %lt1\H, %c\H, ZERO            # lit: facing the light
        and     %lit\H, %lt1\H, %vis\H        # and not occluded
        fm      %x\H, %nn\H, %ll\H            # 1 / sqrt(dot(N, N) dot(L, L)): estimate
        frsqest %y0\H, %x\H                   # and interpolation, 12 bits: the cosine's
        fi      %y\H, %x\H, %y0\H              # error, under 2^-11, is below an 8-bit
        fm      %cs1\H, %c\H, %y\H            # level; cosine, at most 1, 0 when unlit
        fcgt    %big\H, %cs1\H, $125
        selb    %cs2\H, %cs1\H, $125, %big\H
        and     %cs\H, %cs2\H, %lit\H
        fma     %or\H, %cs\H, $73, %ir\H      # a black light adds exactly 0
        fma     %og\H, %cs\H, $74, %ig\H
        fma     %ob\H, %cs\H, $75, %ib\H
      ~ stqd    %or\H, SH_IRR_R+\H(%gp)
      ~ stqd    %og\H, SH_IRR_G+\H(%gp)
      ~ stqd    %ob\H, SH_IRR_B+\H(%gp)
        lqd     %m\H, SH_MAT+\H(%gp)
        ceq     %sel\H, %m\H, $87            # this shader's rays
        fa      %ra\H, %or\H, $124         # kd * (ambient + irradiance), clamped,
        fa      %ga\H, %og\H, $124
        fa      %ba\H, %ob\H, $124
        fm      %rk\H, %ra\H, $121         # to 8 bits: (c 255 + 0.5) truncated, c at
        fm      %gk\H, %ga\H, $122         # most 1: c 255 + 0.5 in 8.24 fixed point,
        fm      %bk\H, %ba\H, $123         # which saturates at 256 (0xffffffff) and
        fma     %rs\H, %rk\H, $106, $126    # is 255.x from c = 1 to there: its top
        cfltu   %ru\H, %rs\H, 24           # byte is the channel
        fma     %gs\H, %gk\H, $106, $126
        cfltu   %gu\H, %gs\H, 24
        fma     %bs\H, %bk\H, $106, $126
        cfltu   %bu\H, %bs\H, 24
        shufb   %rg\H, %ru\H, %gu\H, $88     # the top bytes: r, g, -, 0xff
        shufb   %col\H, %rg\H, %bu\H, $89    # r, g, b, 0xff
        lqd     %o\H, \H(%op)
        selb    %o2\H, %o\H, %col\H, %sel\H
      ~ stqd    %o2\H, \H(%op)
        selb    %mn\H, %m\H, %none, %sel\H    # these rays are shaded
      ~ stqd    %mn\H, SH_MAT+\H(%gp)
        and     $86, $86, %mn\H
        .endr
        ai      $67, $67, 64
        ceqi    %end, $67, 256
        ila     %loop, .Lsh_shade_g
        ila     %exit, .Lsh_shade_end
        selb    %to, %loop, %exit, %end       # (a hinted exit: no miss at the end)
        hbr     .Lsh_shade_br, %to
.Lsh_shade_br:
        bi      %to
        .endsched
.Lsh_shade_end:
        lqd     $84, SH_RUN+16($66)
        ceqi    $77, $86, -1                  # no material left: done
        lqd     $82, SH_RUN($66)
        gb      $77, $77
        lqd     $110, SH_RUN+32($66)
        ceqi    $77, $77, 15
        SH_ADDI $85, $66, SH_IRR_R            # the sums are stored now
        brz     $84, 2f                       # a later pass (or no light) is one run
        ai      $82, $82, 96
        ai      $83, $83, 256
        ai      $84, $84, -1
        brnz    $84, .Lsh_run                 # the next light
2:      brz     $77, .Lsh_pass                # a material left: its pass

        # ---- 4. put the block to ea_colour + packet * 256
.Lsh_done:
        lqd     $70, SH_RUN+48($66)           # the block's EA, tag
        lqd     $74, SH_STATS+SHS_PACKETS($66)
        hbr     .Lsh_ret, $0
        il      $71, 256
        il      $72, 0x20
        rotqbyi $116, $70, 4
        ai      $74, $74, 1
        wrch    $MFC_LSA, $115
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $70
        wrch    $MFC_Size, $71
        wrch    $MFC_TagID, $116
        wrch    $MFC_Cmd, $72
        stqd    $74, SH_STATS+SHS_PACKETS($66)
.Lsh_ret:
        bi      $0

        # ---- out of line: the slow path, no light, a material miss

        # the slow path: an empty or mixed group, or a cache miss
.Lsh_slow:
        ai      $67, $67, -32
.Lsh_slow_group:                              # a group the fast path did not do
        lqd     $77, SH_SCRATCH+144($66)
        a       $76, $99, $67
        andi    $75, $67, 16
        lqd     $74, CTX_RAY_ID($76)          # (its ids, while the flag loads)
        rotmi   $75, $75, -1
        rotqby  $77, $77, $75
        ceqi    $74, $74, -1
        gb      $75, $74
        ceqi    $75, $75, 15
        brnz    $77, .Lsh_slow_next
        brnz    $75, .Lsh_slow_empty

        # Rays on different triangles, every lane's record and vertices in the caches (the
        # same lookups speculatively, lane by lane), the lanes' rows transposed into
        # columns by pairs of lanes; otherwise (a cache miss, no hit at all) the lanes one
        # by one below. (Its pool takes $92, $93 and $120 too: reloaded after.)
        .sched  pool=68-90,92-96,98,100-106,110-114,116-118,120,125-127 scratch=66-127
        a       %rp, $99, $67
        a       %gp, $66, $67
        lqd     %ids, CTX_RAY_ID(%rp)
        lqa     %plo, sh_const
        lqa     %phi, sh_const+16
        lqa     %psnd, sh_const+48
        ceqi    %miss, %ids, -1
        gb      %mb, %miss
        ceqi    %allm, %mb, 15
        shufb   %s0, %ids, %ids, $91
        ceq     %same, %ids, %s0
        gb      %sameb, %same
        ceqi    %samec, %sameb, 15
        or      %nogo, %allm, %samec
        rotqbyi %r4, %ids, 4                  # a lane without a hit looks up the
        cgt     %c4, %ids, %r4                # largest id of the group (a hit's)
        selb    %m4, %r4, %ids, %c4
        rotqbyi %r8, %m4, 8
        cgt     %c8, %m4, %r8
        selb    %mx, %r8, %m4, %c8
        shufb   %mxs, %mx, %mx, $91
        selb    %idv, %ids, %mxs, %miss
        .irp    P, 0, 8                       # pairs of lanes: 0 and 4, 8 and 12
        .irp    J, 0, 4
        rotqbyi %id\P\()_\J, %idv, \P+\J
        and     %ti\P\()_\J, %id\P\()_\J, TMASK
        shli    %to\P\()_\J, %ti\P\()_\J, 4
        lqx     %tag\P\()_\J, TTAGS, %to\P\()_\J
        shli    %tl\P\()_\J, %ti\P\()_\J, 6
        a       %line\P\()_\J, %tl\P\()_\J, TDATA
        ceq     %th\P\()_\J, %tag\P\()_\J, %id\P\()_\J
        lqd     %q3\P\()_\J, 48(%line\P\()_\J)
        and     %vi\P\()_\J, %q3\P\()_\J, $121
        shli    %vo0\P\()_\J, %vi\P\()_\J, 4
        shli    %vl0\P\()_\J, %vi\P\()_\J, 6
        rotqbyi %vo1\P\()_\J, %vo0\P\()_\J, 4
        rotqbyi %vo2\P\()_\J, %vo0\P\()_\J, 8
        rotqbyi %vl1\P\()_\J, %vl0\P\()_\J, 4
        rotqbyi %vl2\P\()_\J, %vl0\P\()_\J, 8
        lqx     %vt0\P\()_\J, $115, %vo0\P\()_\J
        lqx     %vt1\P\()_\J, $115, %vo1\P\()_\J
        lqx     %vt2\P\()_\J, $115, %vo2\P\()_\J
        rotqbyi %q3b\P\()_\J, %q3\P\()_\J, 4
        rotqbyi %q3c\P\()_\J, %q3\P\()_\J, 8
        ceq     %h0\P\()_\J, %vt0\P\()_\J, %q3\P\()_\J
        ceq     %h1\P\()_\J, %vt1\P\()_\J, %q3b\P\()_\J
        ceq     %h2\P\()_\J, %vt2\P\()_\J, %q3c\P\()_\J
        and     %h01\P\()_\J, %h0\P\()_\J, %h1\P\()_\J
        and     %h012\P\()_\J, %h01\P\()_\J, %h2\P\()_\J
        and     %okl\P\()_\J, %h012\P\()_\J, %th\P\()_\J
        .endr
        and     %ok\P, %okl\P\()_0, %okl\P\()_4
        .endr
        and     %ok03, %ok0, %ok8
        andc    %ok, %ok03, %nogo
        brz     %ok, .Lsh_slow_body           # a miss: no row is loaded
        .irp    P, 0, 8
        .irp    J, 0, 4
        lqx     %n0\P\()_\J, $123, %vl0\P\()_\J
        lqx     %n1\P\()_\J, $123, %vl1\P\()_\J
        lqx     %n2\P\()_\J, $123, %vl2\P\()_\J
        fs      %d1\P\()_\J, %n1\P\()_\J, %n0\P\()_\J           # n1 - n0, n2 - n0
        fs      %d2\P\()_\J, %n2\P\()_\J, %n0\P\()_\J
        lqd     %q0\P\()_\J, 0(%line\P\()_\J)
        lqd     %q1\P\()_\J, 16(%line\P\()_\J)
        lqd     %q2\P\()_\J, 32(%line\P\()_\J)
        shufb   %kq\P\()_\J, %q0\P\()_\J, %q3\P\()_\J, %phi     # words 2, 3: k (q0 word 3), the material (q3's)
        .endr
        .irp    R, q1, q2, n0, d1, d2         # rows by pairs of lanes: b, c, n0, n1 - n0, n2 - n0
        shufb   %lo\P\R, %\R\()\P\()_0, %\R\()\P\()_4, %plo
        shufb   %hi\P\R, %\R\()\P\()_0, %\R\()\P\()_4, %phi
        .endr
        shufb   %kq\P, %kq\P\()_0, %kq\P\()_4, %phi
        .endr
        # the columns: b and c (q1, q2 words 0-2), n0, n1 - n0, n2 - n0 (x, y, z); k and
        # the material
        .irp    R, q1, q2, n0, d1, d2
        shufb   %c0\R, %lo0\R, %lo8\R, $119
        shufb   %c1\R, %lo0\R, %lo8\R, %psnd
        shufb   %c2\R, %hi0\R, %hi8\R, $119
        .endr
        shufb   %k, %kq0, %kq8, $119
        shufb   %mc, %kq0, %kq8, %psnd
        or      %mat, %mc, %miss              # no hit: no material
      ~ stqd    %mat, SH_MAT(%gp)
        SH_GROUP_COLUMNS %k, %c0q1, %c1q1, %c2q1, %c0q2, %c1q2, %c2q2, %c0n0, %c1n0, %c2n0, %c0d1, %c1d1, %c2d1, %c0d2, %c1d2, %c2d2
        cntb    %mc1, %mb                     # counted: a group, its hit lanes
        sfi     %hits, %mc1, 4
        lqd     %cg, SH_STATS+SHS_GROUPS($66)
        lqd     %ct, SH_STATS+SHS_TLOOK($66)
        ai      %cg1, %cg, 1
        a       %ct1, %ct, %hits
        stqd    %cg1, SH_STATS+SHS_GROUPS($66)
        stqd    %ct1, SH_STATS+SHS_TLOOK($66)
        hbrr    .Lsh_mixed_br, .Lsh_slow_next
.Lsh_mixed_br:
        br      .Lsh_slow_next
        .endsched

        # one lane at a time
.Lsh_slow_body:
        .sched  pool=74-77,79,90,94 scratch=66-127
        ila     %so, SH_SAVE
        a       %sv, $66, %so
        .irp    R, 0, 1, 2, 3, 4
        stqd    $12\R, 16*\R(%sv)
        .endr
        lqd     %blk, SH_BLOCK($66)           # its registers (the fast path's pool)
        ori     $100, %blk, 0                 # vertices
        lqa     $117, sh_const
        lqa     $118, sh_const+16
        lqa     $98, sh_const+48
        ila     %io, CTX_RAY_ID
        a       $111, $99, %io
        ori     $113, $99, 0
        ila     $114, sh_vertex_miss
        ila     $106, sh_tri_miss
        ila     %vo, SH_VDATA
        a       $116, $66, %vo
        lqx     $70, $111, $67                # ids
        ceqi    $78, $70, -1                  # misses
        gb      $72, $78
        ceqi    $73, $72, 15
        .endsched
        brnz    $73, .Lsh_group_empty
        shufb   $74, $70, $70, $91
        ceq     $75, $70, $74
        gb      $75, $75
        ceqi    $75, $75, 15                  # the same triangle in all four lanes
        lqd     $74, SH_STATS+SHS_GROUPS($66)
        lqd     $76, SH_STATS+SHS_TLOOK($66)
        cntb    $79, $72                      # lanes without a hit
        sfi     $79, $79, 4                   # the records looked up: one per hit lane,
        il      $77, 1                        # or the group's one
        selb    $79, $79, $77, $75
        ai      $74, $74, 1
        a       $76, $76, $79
        stqd    $74, SH_STATS+SHS_GROUPS($66)
        stqd    $76, SH_STATS+SHS_TLOOK($66)
        stqd    $75, SH_SAME($66)             # (kept over the fetches)
        ila     $77, .Lsh_lanes               # the lanes one by one, or the group's one
        ila     $79, .Lsh_same                # triangle: a branch hinted either way
        selb    $77, $77, $79, $75
        hbr     .Lsh_pick, $77
        SH_FETCH 0
.Lsh_pick:
        bi      $77
.Lsh_same:
        SH_WAIT $74
        SH_NORMALS 0
        SH_LAND
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
        SH_WAIT $74
        .irp    L, 0, 1, 2, 3
        SH_NORMALS \L
        .endr
        SH_LAND
.Lsh_fetched:
        # the lanes' records and normals as columns (4x4 transposes: $117, $118 pair the
        # rows' words, $119, $98 take the columns); k (record word 3), b and c (words
        # 4-6, 8-10), the material (word 15)
        .sched  pool=70-77,79-90,94-95,120-121,123-127 scratch=66-127
        .irp    Q, 0, 16, 32, 48, 256, 272, 288   # then the normals (SH_NRM)
        lqd     %ra\Q, SH_STAGE+\Q($66)
        lqd     %rb\Q, SH_STAGE+64+\Q($66)
        lqd     %rc\Q, SH_STAGE+128+\Q($66)
        lqd     %rd\Q, SH_STAGE+192+\Q($66)
        shufb   %hab\Q, %ra\Q, %rb\Q, $118
        shufb   %hcd\Q, %rc\Q, %rd\Q, $118
        .endr
        .irp    Q, 16, 32, 256, 272, 288
        shufb   %lab\Q, %ra\Q, %rb\Q, $117
        shufb   %lcd\Q, %rc\Q, %rd\Q, $117
        shufb   %w0\Q, %lab\Q, %lcd\Q, $119
        shufb   %w1\Q, %lab\Q, %lcd\Q, $98
        shufb   %w2\Q, %hab\Q, %hcd\Q, $119
        .endr
        .irp    Q, 0, 48
        shufb   %w3\Q, %hab\Q, %hcd\Q, $98
        .endr
        a       %gp, $66, $67
        a       %rp, $113, $67
        or      %mat, %w348, $78              # misses: no material
      ~ stqd    %mat, SH_MAT(%gp)
        # the normal n0 + beta (n1 - n0) + gamma (n2 - n0) (vertex i: w0, w1, w2 of
        # 256 + 16 i), turned to the eye
        fs      %d1x, %w0272, %w0256          # n1 - n0
        fs      %d1y, %w1272, %w1256
        fs      %d1z, %w2272, %w2256
        fs      %d2x, %w0288, %w0256          # n2 - n0
        fs      %d2y, %w1288, %w1256
        fs      %d2z, %w2288, %w2256
        SH_GROUP_COLUMNS %w30, %w016, %w116, %w216, %w032, %w132, %w232, %w0256, %w1256, %w2256, %d1x, %d1y, %d1z, %d2x, %d2y, %d2z
        .endsched
.Lsh_slow_done:
        SH_ADDI $74, $66, SH_SAVE
        .irp    R, 0, 1, 2, 3, 4
        lqd     $12\R, 16*\R($74)
        .endr
.Lsh_slow_next:
        hbrr    .Lsh_slow_back, .Lsh_group    # (after the pair's second group)
        lqa     $92, sh_const+80
        lqa     $93, sh_const+96
        lqa     $120, sh_const+208
        ai      $67, $67, 16
        andi    $74, $67, 16
        brnz    $74, .Lsh_slow_group
        ceqi    $74, $67, 256
.Lsh_slow_back:
        brz     $74, .Lsh_group
        br      .Lsh_iset_done
.Lsh_group_empty:                             # no hit: no material
        SH_ADDI $74, $66, SH_MAT
        stqx    $78, $74, $67
        br      .Lsh_slow_done
.Lsh_slow_empty:                              # no hit: no material
        SH_ADDI $75, $66, SH_MAT
        stqx    $74, $75, $67
        br      .Lsh_slow_next

        # ---- the first call: fetch the block, splat the lights, clear counters and caches
.Lsh_empty:                                   # no ray hit
        il      $70, -1
        SH_ADDI $71, $66, SH_MAT
        .irp    Q, 0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 208, 224, 240
        stqd    $70, \Q($71)
        .endr
        br      .Lsh_iset_done

.Lsh_first:
        stqd    $68, SH_FLAG($66)
        SH_ADDI $72, $66, SH_BLOCK
        il      $73, SHADING_BLOCK_BYTES
        SH_GET  $72, $71, $73, $74
        SH_ADDI $71, $66, SH_DCOUNT
        stqd    ZERO, 0($71)                  # no vertex in flight
        il      $71, 10
        SH_FILL ZERO, SH_STATS
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
        .irp    W, 74, 75                     # position, colour: x, y, z splats
        .irp    P, 91, 92, 93
        shufb   $76, $\W, $\W, $\P
        stqd    $76, (\W-74)*48+(\P-91)*16($73)
        .endr
        .endr
        ai      $72, $72, SHB_LIGHT_BYTES
        ai      $73, $73, 96
        ai      $71, $71, -1
        brnz    $71, 1b
2:      il      $74, -1                       # every light visible (no shadow rays)
        il      $71, 8 * 16
        SH_FILL $74, SH_VIS
        lqd     $70, SH_BLOCK+SHB_MODE($66)   # mode, early, vertex log2, material log2
        il      $74, -1
        il      $75, 1
        rotqbyi $71, $70, 8
        shl     $71, $75, $71                 # vertex entries
        SH_FILL $74, SH_VTAGS
        rotqbyi $71, $70, 8
        shl     $71, $75, $71
        ai      $71, $71, -1
        shufb   $121, $71, $71, $91           # the vertex index mask in every lane
        stqd    $121, SH_VMASK($66)
        rotqbyi $71, $70, 12
        shl     $71, $75, $71                 # material entries
        SH_FILL $74, SH_MTAGS
        br      .Lsh_ready

.Lsh_mmiss:                                   # a material cache miss
        shli    $74, $110, 5
        a       $74, $74, $101
        il      $75, 32
        SH_GET  $73, $74, $75, $76
        stqd    $110, 0($72)
        SH_COUNT SHS_MMISS, $76
        br      .Lsh_mhit


# a vertex cache miss: vertex $81 into line $84, tag $83, its normal for $66 + $89; back
# to $88. The fetch is queued, not waited for, into a staging slot of its own; the tag
# becomes the vertex with bit 31 set (in flight) and the miss is counted. A copy is left
# to SH_LAND, which the slow path runs once the group's lanes are looked up: one
# wait for all their misses, then in lookup order each slot's normal (the one quadword
# of a vertex record the module reads) to its line (so a line ends up with the last
# vertex looked up there) and to the lane, and the vertex to the line's tag (landed). A
# lookup of a vertex in flight is no miss: its copy comes from its line, after the slot's
# (it leaves by the hinted return, which was 43% of the calls in the beetle).
# (Uses $71-$77, $82, $85-$87, $90, $94, $125-$127.)
sh_vertex_miss:
        .sched  pool=71-77,85-87,90,125-127 scratch=66-127
        hbr     .Lsh_vm_ret, $88
        ila     %o1, SH_DCOUNT
        a       %dc, $66, %o1
        lqd     %n, 0(%dc)                    # bytes of copies (32 each)
        lqd     %tag, 0($83)
        ilhu    %hb, 0x8000
        or      $94, $81, %hb                 # the vertex, in flight
        ceq     %inf, %tag, $94
        ila     %o2, SH_VSTAGE
        a       %sb, $66, %o2
        shli    %n2, %n, 1
        a       $82, %n2, %sb                 # its slot
        selb    %src, $82, $84, %inf          # in flight already: from its line
        a       %lane, $89, $66
        lqa     %plo, sh_const
        lqa     %pfh, sh_const+32
        lqa     %p1, sh_const+336
        shufb   %ll, %lane, %lane, %plo
        shufb   %tv, $83, $81, %plo
        shufb   %ltv, %ll, %tv, %pfh          # (-, the lane, the tag, the vertex), then
        shufb   %rec, %src, %ltv, %p1         # the source in front: one shuffle after it
        ila     %o3, SH_DEFER
        a       %db, $66, %o3
        a       %d2, %db, %n
        stqd    %rec, 0(%d2)
        stqd    $84, 16(%d2)                  # the line
        ai      %n1, %n, 32
        stqd    %n1, 0(%dc)
        brnz    %inf, .Lsh_vm_ret             # (the return hinted either way)
        .endsched
        .sched  pool=71-77,85-87,90,125-127 scratch=66-127
        lqd     %cnt, SH_STATS+SHS_VMISS($66)
        shli    %ea0, $81, 6
        a       %ea, %ea0, $100
        il      %size, 64
        il      %tg, SH_TAG
        il      %cmd, 0x40
        ai      %cnt1, %cnt, 1
        wrch    $MFC_LSA, $82
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, %ea
        wrch    $MFC_Size, %size
        wrch    $MFC_TagID, %tg
        wrch    $MFC_Cmd, %cmd
        stqd    $94, 0($83)                   # the tag: in flight
        stqd    %cnt1, SH_STATS+SHS_VMISS($66)
.Lsh_vm_ret:
        bi      $88
        .endsched

# a triangle record the traversal's cache does not hold: record $80 into $82, not waited
# for (SH_WAIT); back to $88
sh_tri_miss:
        hbr     1f, $88
        SH_COUNT SHS_TMISS, $84
        shli    $81, $80, 6
        a       $81, $81, EATRIS
        SH_QUEUE $82, $81, 64, $83
1:      bi      $88
shade_end:
