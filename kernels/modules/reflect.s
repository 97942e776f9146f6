# reflect.s — reflection rays (--shade reflect; the paper's section 7: "each 8x8 primary
# packet generates one reflection packet"): the packet's hits on reflective materials cast
# reflected rays, which are traced by the primary rays' traversal and triangle test through
# the same caches, shaded by the shading module with shadows, and blended in by the
# reflectance, up to the frame's depth. Model: loader/src/reflection.rs.
#
# Levels: 0 is the primary packet, level k its k-th reflection. `reflect_packet` takes the
# place of shade.s's entry in packet_done (output.s) and runs, per level, the shading module
# (which keeps its colour block here, reflect_block, instead of putting it) and then traces
# the next level's rays; at the end it blends the levels' colours from the deepest up and
# puts the packet's colours. Inside the shading module, once the i-set is built,
# `reflect_iset` turns a reflection's normals to face its rays and generates the next
# level's rays from the i-set: R = d - 2 (d.N / N.N) N, from P + REFLECT_OFFSET R, cast
# where the hit's material reflects (its reflectance from a per-material table in local
# store, fetched once).
#
# The reflected rays of a packet have no common origin, and the traversal, the triangle
# test and the i-set all take one origin per packet. So each reflected ray is traced as a
# packet of its own (one lane active, every other ray t = -1, as shadow.s's rays
# that are not cast), in the reflection area's packet context with blocking misses, as
# shadow.s traces its packets; packet_done comes back to `reflect_ray_done` while rf_trace
# is set. The ray is the packet's ray RF_RAY (below). A level's hits go to the shading module as a packet whose rays are the hit points
# from origin 0 (d = O + t R, t = 1: the i-set's hit point is then the hit point itself, and
# its barycentrics are the record's projection of it); the i-set turns the normal to face
# that d, which reflect_iset turns to face R. Each level's hits (record, t) are put to the
# frame's bounce-hit buffer for the host's validation.
#
# The reflection area (REFLECT_AREA above the shading area; loader::kernel_abi::ReflectArea,
# RF_* in layout.inc): the level, the ray being traced, the rays cast, the saved miss
# handlers and registers, the statistics before the level, per bounce the counters, the
# reflectance table, per level the weights and colour blocks, the next level's rays, the
# traced level's hits, the hits as shading rays, the reflected rays' packet context.

        .text
        .align  4
rf_trace:       .long 0, 0, 0, 0        # all ones while a reflected ray is traced
rf_hold:        .long 0, 0, 0, 0        # all ones: the shading module keeps its block
rf_origin:      .long 0, 0, 0, 0        # the origin the i-set adds (shade.s)
rf_ready:       .long 0, 0, 0, 0        # all ones once the counters are cleared
rf_saved:       .long 0, 0, 0, 0        # all ones: the packet's registers are saved
rf_refl:        .long 0x5245464c, 0x5245464c, 0x5245464c, 0x5245464c   # "REFL"
rf_corner_x:    .float 1.0, -1.0, 1.0, -1.0
rf_corner_y:    .float 0.375, -0.375, 0.375, -0.375
rf_corner_z:    .float 0.6875, -0.6875, 0.6875, -0.6875
rf_tag:         .long REFLECT_TAG, 1 << REFLECT_TAG, 0, 0
rf_minus1:      .float -1.0, -1.0, -1.0, -1.0
rf_offset:      .long REFLECT_OFFSET_BITS, REFLECT_OFFSET_BITS, REFLECT_OFFSET_BITS, REFLECT_OFFSET_BITS
rf_half:        .float 0.5, 0.5, 0.5, 0.5
rf_pair:        .long 0x00010203, 0x10111213, 0x00010203, 0x10111213   # (a0, b0, a0, b0)
rf_word2:       .long 0, 0, -1, 0
rf_halves:      .long 0x00010203, 0x04050607, 0x10111213, 0x14151617   # (a0, a1, b0, b1)

# the registers the reflected rays' traversal changes and packet_done keeps (as shadow.s's,
# less shade.s's and the link, saved on its own): the context and the packet's own of
# regs.inc. Saved only for a packet that traces reflected rays.
        .macro  RF_EACH_REG op, base
        .irp    R, 1, 6, 11, 25, 27, 28, 29, 33, 34, 35, 39, 40, 42, 43, 44, 45, 46, 47, 48
        \op     $\R, RF_REGS+16*\R(\base)
        .endr
        .irp    R, 49, 50, 51, 52, 53, 54, 55, 56, 57, 58, 59, 60, 61, 62, 63, 64, 65
        \op     $\R, RF_REGS+16*\R(\base)
        .endr
        .endm

# $rt = the shading area (from params), $rb = the reflection area
        .macro  RF_AREAS rt, rb
        ila     \rb, params
        lqd     \rt, PARAM_SHADING_QUAD(\rb)
        rotqbyi \rt, \rt, PARAM_SHADING_ROT + 4
        ila     \rb, REFLECT_AREA
        a       \rb, \rb, \rt
        .endm

# wait for the puts on tag TAG (tmp: a scratch register)
        .macro  RF_WAIT tag, tmp
        il      \tmp, 1 << \tag
        wrch    $MFC_WrTagMask, \tmp
        il      \tmp, 2
        wrch    $MFC_WrTagUpdate, \tmp
        rdch    \tmp, $MFC_RdTagStat
        .endm

# The ray's place in its packet: ray 48 (vector 12, lane 0), the first of the last group
# of 16, so that a leaf tests that group only (triangle.s tests from the first active
# ray's group to the end: from ray 0, all 64 rays per triangle)
        .set    RF_RAY, 48
        .set    RF_SLOT, 16 * (RF_RAY / 4)

# ---- a traced primary packet (from packet_done): $68 = its rays, $69 = its number, $0 the
# return. Keeps $1..$65 as shade_packet does.
        .align  3
reflect_packet:
        RF_AREAS $66, $70
        stqd    $0, RF_REGS($70)
        stqd    $68, RF_REGS+16*68($70)       # (the slots of registers not kept)
        stqd    $69, RF_REGS+16*69($70)
        lqa     $71, rf_ready
        brz     $71, .Lrf_clear
.Lrf_start:
        ila     $71, params
        lqd     $72, PARAM_ORIGIN($71)
        stqa    $72, rf_origin                # the primary rays' origin for the i-set
        stqd    ZERO, RF_STATE($70)           # level 0
        stqd    ZERO, RF_CASTS($70)
        il      $72, -1
        stqa    $72, rf_hold
        hbrr    .Lrf_shade0, shade_packet
.Lrf_shade0:
        brsl    $0, shade_packet              # level 0's colours and level 1's rays
        RF_AREAS $66, $70
        lqd     $74, RF_CASTS($70)
        brz     $74, .Lrf_put                 # no reflected ray: level 0's colours
        RF_EACH_REG stqd, $70                 # the registers the rays' traversal changes
        il      $75, -1
        stqa    $75, rf_saved

# ---- the next level, if the last one cast any ray and the depth allows
.Lrf_level:
        RF_AREAS $66, $70
        lqd     $71, RF_STATE($70)
        lqd     $72, SH_BLOCK+SHB_REFLECT($66)
        ceq     $73, $71, $72
        brnz    $73, .Lrf_blend
        lqd     $74, RF_CASTS($70)
        brz     $74, .Lrf_blend
        # the one-context miss handlers while the reflected rays run (as shadow.s)
        .irp    W, 0, 1, 2, 3
        lqa     $75, vars+V_BMISSH+16*\W      # V_BMISSH, V_BFETCH, V_PFMISS, V_PFFETCH
        stqd    $75, RF_HANDLERS+16*\W($70)
        .endr
        lqa     $75, vars+V_NCTX1
        stqd    $75, RF_HANDLERS+16*4($70)
        lqa     $76, vars+V_ASSOC4
        il      $77, -1
        stqa    $77, vars+V_NCTX1
        ila     $77, .Lb_one_fetch
        stqa    $77, vars+V_BFETCH
        ila     $77, .Lpf_one_evict
        stqa    $77, vars+V_PFFETCH
        ila     $77, bvh_miss_one
        ila     $78, bvh_miss_ways
        selb    BMISSH, $77, $78, $76
        stqa    BMISSH, vars+V_BMISSH
        ila     $77, .Lpf_one
        ila     $78, .Lpf_ways
        selb    $77, $77, $78, $76
        stqa    $77, vars+V_PFMISS
        # the reflected rays' context
        ila     $77, REFLECT_CTX
        a       RAYS, $66, $77
        ai      NEGTAB, RAYS, CTX_NEGTAB
        ila     $77, CTX_STACK
        a       STKBASE, RAYS, $77
        lqa     $77, rf_tag
        stqd    $77, CTX_TAG(RAYS)
        lqa     $77, rf_corner_x              # no corner-ray culling (as shadow.s)
        stqd    $77, CTX_CORNERS(RAYS)
        lqa     $77, rf_corner_y
        stqd    $77, CTX_CORNERS+16(RAYS)
        lqa     $77, rf_corner_z
        stqd    $77, CTX_CORNERS+32(RAYS)
        # the statistics so far (the level's work is the difference)
        stqd    S_STEPS, RF_BEFORE($70)
        lqa     $77, vars+V_BMISS
        stqd    $77, RF_BEFORE+16($70)
        lqa     $77, vars+V_LEAVES
        stqd    $77, RF_BEFORE+32($70)
        stqd    S_TLOOK, RF_BEFORE+48($70)
        lqa     $77, vars+V_TMISS
        stqd    $77, RF_BEFORE+64($70)
        RF_WAIT 7, $77                        # the last level's hits are out
        # every ray of the context inactive (t = -1, no hit, finite d and 1/d): a ray's
        # packet then writes its own vector only
        lqa     $78, rf_minus1
        il      $79, -1
        .irp    V, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15
        .irp    A, CTX_RAY_DX, CTX_RAY_DX+256, CTX_RAY_DX+512, CTX_RAY_RX, CTX_RAY_RX+256, CTX_RAY_RX+512
        stqd    ONE, \A+16*\V(RAYS)
        .endr
        stqd    $78, CTX_RAY_T+16*\V(RAYS)
        stqd    $79, CTX_RAY_ID+16*\V(RAYS)
        .endr
        stqd    ZERO, RF_TRACE($70)
        il      $77, -1
        stqa    $77, rf_trace

# ---- the next ray the level casts: its packet of one ray, traced
.Lrf_next:
        RF_AREAS $66, $70
        lqd     $71, RF_TRACE($70)
        ila     $75, RF_CAST
        a       $75, $75, $70
1:      ceqi    $72, $71, 64
        brnz    $72, .Lrf_traced
        rotmi   $73, $71, -2
        shli    $73, $73, 4                   # its vector's offset
        andi    $74, $71, 3
        shli    $74, $74, 2                   # its lane * 4
        lqx     $76, $75, $73
        rotqby  $76, $76, $74
        brz     $76, .Lrf_skip                # (a lane that casts none: out of line)
        stqd    $71, RF_TRACE($70)
        # its origin and direction, splatted; 1/d; the packet's vector RF_SLOT (lane 0 the
        # ray, t = 1e30, the other lanes t = -1); the frustum of the ray's own 1/d on every
        # axis (raygen.s's packet setup)
        .sched  pool=76-99,113-127 scratch=66-127
        shli    %l16, $74, 2
        ila     %kp, k_pat
        lqx     %pat, %kp, %l16               # the lane's splat pattern
        a       %base, $70, $73
        ila     %oo, RF_OX
        a       %ob, %oo, %base
        ila     %dd, RF_DX
        a       %db, %dd, %base
        lqd     %ox, 0(%ob)
        lqd     %oy, 256(%ob)
        lqd     %oz, 512(%ob)
        lqd     %dx, 0(%db)
        lqd     %dy, 256(%db)
        lqd     %dz, 512(%db)
        shufb   OXS, %ox, %ox, %pat
        shufb   OYS, %oy, %oy, %pat
        shufb   OZS, %oz, %oz, %pat
        shufb   %sx, %dx, %dx, %pat
        shufb   %sy, %dy, %dy, %pat
        shufb   %sz, %dz, %dz, %pat
        fsmbi   %m0, 0xf000
        fsmbi   %m1, 0x0f00
        fsmbi   %m2, 0x00f0
        selb    %o0, ZERO, OXS, %m0           # (x, y, z, 0)
        selb    %o1, %o0, OYS, %m1
        selb    ORIG, %o1, OZS, %m2
        lqa     %m1s, rf_minus1
        lqa     %w0, k_word0
        selb    %t0, %m1s, BIG, %w0
        il      %none, -1
        lqa     %eps, k_eps
        lqa     %e20, k_eps20
        lqa     %abs, k_abs
        .irp    K, x, y, z
        frest   %y\K, %s\K
        fi      %y\K, %s\K, %y\K
        fnms    %e\K, %s\K, %y\K, ONE
        fma     %r\K, %e\K, %y\K, %y\K
        .endr
        stqd    %sx, CTX_RAY_DX+RF_SLOT(RAYS)
        stqd    %sy, CTX_RAY_DX+256+RF_SLOT(RAYS)
        stqd    %sz, CTX_RAY_DX+512+RF_SLOT(RAYS)
        stqd    %rx, CTX_RAY_RX+RF_SLOT(RAYS)
        stqd    %ry, CTX_RAY_RX+256+RF_SLOT(RAYS)
        stqd    %rz, CTX_RAY_RX+512+RF_SLOT(RAYS)
        stqd    %t0, CTX_RAY_T+RF_SLOT(RAYS)
        stqd    %none, CTX_RAY_ID+RF_SLOT(RAYS)
        stqd    %sx, CTX_CORNERS(RAYS)        # the corner rays: the ray itself
        stqd    %sy, CTX_CORNERS+16(RAYS)
        stqd    %sz, CTX_CORNERS+32(RAYS)
        fm      PAX, %rx, %eps
        fm      PAY, %ry, %eps
        fm      PAZ, %rz, %eps
        .irp    K, 0, 1, 2
        ori     (\K+PBX), (\K+PAX), 0
        fm      %p\K, (\K+OXS), (\K+PAX)
        and     %a\K, %p\K, %abs
        fma     %q\K, %a\K, %e20, %p\K
        fs      (\K+OAX), ZERO, %q\K
        ori     (\K+OBX), (\K+OAX), 0
        .endr
        lqa     %odd, k_oddmask
        and     F2, NBIG, %odd
        .endsched
        hbrr    .Lrf_trav_br, trav
        ori     STK, STKBASE, 0
        il      FIRST, RF_RAY
        SET_FIRST
        lqa     $108, rf_word2
        selb    CUR, ROOTST, FIRST, $108      # the root, with the ray as its first
        lqa     BMISSH, vars+V_BMISSH         # (a leaf's ray loop uses the register)
        lqa     $107, vars+V_EMPTY
        brnz    $107, packet_done             # the empty scene: a miss
.Lrf_trav_br:
        br      trav
.Lrf_skip:
        ai      $71, $71, 1
        br      1b

# ---- the reflected ray is done (packet_done comes here while rf_trace is set): its hit
# (lane 0's record and t) to its lane of the level's hits, then the next ray
reflect_ray_done:
        .sched  pool=71-127 scratch=66-127
        ila     %p, params
        lqd     %q, PARAM_SHADING_QUAD(%p)
        rotqbyi $66, %q, PARAM_SHADING_ROT + 4
        ila     %ra, REFLECT_AREA
        a       $70, %ra, $66
        lqd     %i, RF_TRACE($70)
        rotmi   %v, %i, -2
        shli    %vo, %v, 4
        andi    %l, %i, 3
        shli    %lo, %l, 2
        ila     %hi, RF_HIT_ID
        a       %h1, %hi, $70
        a       %h2, %h1, %vo
        a       %w, %h2, %lo                  # the ray's word of the hit ids
        lqd     %id, CTX_RAY_ID+RF_SLOT(RAYS)
        lqd     %t, CTX_RAY_T+RF_SLOT(RAYS)
        cwd     %ins, 0(%w)
        lqd     %ids, 0(%w)
        shufb   %ids2, %id, %ids, %ins
        stqd    %ids2, 0(%w)
        lqd     %ts, 256(%w)                  # (RF_HIT_T follows RF_HIT_ID)
        shufb   %ts2, %t, %ts, %ins
        stqd    %ts2, 256(%w)
        ai      %i1, %i, 1
        hbrr    .Lrd_br, .Lrf_next
      ! stqd    %i1, RF_TRACE($70)
        .endsched
.Lrd_br:
        br      .Lrf_next

# ---- the level is traced: the handlers back, its counters, its hits put and handed to
# the shading module as rays from origin 0
.Lrf_traced:
        stqa    ZERO, rf_trace
        .irp    W, 0, 1, 2, 3
        lqd     $75, RF_HANDLERS+16*\W($70)
        stqa    $75, vars+V_BMISSH+16*\W
        .endr
        lqd     $75, RF_HANDLERS+16*4($70)
        stqa    $75, vars+V_NCTX1
        lqd     $71, RF_STATE($70)            # the level: bounce level + 1's counters
        shli    $72, $71, 7
        ila     $73, RF_COUNTERS
        a       $73, $73, $72
        a       $73, $73, $70
        lqd     $74, RF_CASTS($70)            # rays
        lqd     $75, 0($73)
        a       $75, $75, $74
        stqd    $75, 0($73)
        lqd     $75, 16($73)                  # packets
        ai      $75, $75, 1
        stqd    $75, 16($73)
        lqd     $76, RF_BEFORE($70)           # pair steps
        sf      $76, $76, S_STEPS
        lqd     $75, 48($73)
        a       $75, $75, $76
        stqd    $75, 48($73)
        lqd     $76, RF_BEFORE+16($70)        # BVH misses
        lqa     $77, vars+V_BMISS
        sf      $76, $76, $77
        lqd     $75, 64($73)
        a       $75, $75, $76
        stqd    $75, 64($73)
        lqd     $76, RF_BEFORE+32($70)        # leaves
        lqa     $77, vars+V_LEAVES
        sf      $76, $76, $77
        lqd     $75, 80($73)
        a       $75, $75, $76
        stqd    $75, 80($73)
        lqd     $76, RF_BEFORE+48($70)        # triangle lookups
        sf      $76, $76, S_TLOOK
        lqd     $75, 96($73)
        a       $75, $75, $76
        stqd    $75, 96($73)
        lqd     $76, RF_BEFORE+64($70)        # triangle misses
        lqa     $77, vars+V_TMISS
        sf      $76, $76, $77
        lqd     $75, 112($73)
        a       $75, $75, $76
        stqd    $75, 112($73)
        # the hits: kept where cast (a record or -1, t), the rest -1 and 0; as shading rays
        # the hit point from origin 0, t = 1
        ila     $80, RF_HIT_ID
        a       $80, $80, $70                 # ids, t at +256
        ila     $81, RF_RAYS
        a       $81, $81, $70                 # the shading rays
        il      $82, -1
        il      $83, 0                        # minus the hits
        .irp    V, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15
        lqd     $84, RF_CAST+16*\V($70)
        lqd     $85, 16*\V($80)
        lqd     $86, 256+16*\V($80)
        ceqi    $87, $85, -1
        andc    $88, $84, $87                 # cast and hit
        selb    $89, $82, $85, $88
        and     $90, $86, $84
        stqd    $89, 16*\V($80)
        stqd    $90, 256+16*\V($80)
        a       $83, $83, $88
        lqd     $91, RF_OX+16*\V($70)
        lqd     $92, RF_OX+256+16*\V($70)
        lqd     $93, RF_OX+512+16*\V($70)
        lqd     $94, RF_DX+16*\V($70)
        lqd     $95, RF_DX+256+16*\V($70)
        lqd     $96, RF_DX+512+16*\V($70)
        fma     $91, $90, $94, $91            # O + t R
        fma     $92, $90, $95, $92
        fma     $93, $90, $96, $93
        stqd    $91, CTX_RAY_DX+16*\V($81)
        stqd    $92, CTX_RAY_DX+256+16*\V($81)
        stqd    $93, CTX_RAY_DX+512+16*\V($81)
        stqd    ONE, CTX_RAY_T+16*\V($81)
        stqd    $89, CTX_RAY_ID+16*\V($81)
        .endr
        rotqbyi $84, $83, 8
        a       $83, $83, $84
        rotqbyi $84, $83, 4
        a       $83, $83, $84
        lqd     $75, 32($73)                  # hits
        sf      $75, $83, $75
        stqd    $75, 32($73)
        # the level's hits to ea_bounce_hits + (packet * depth + level) * 512, tag 7
        lqd     $84, SH_BLOCK+SHB_REFLECT($66) # (depth, the table's EA, the hits' EA)
        rotqbyi $85, $84, 8
        lqd     $86, RF_REGS+16*69($70)       # the packet
        rotmi   $87, $86, -16
        mpyu    $87, $87, $84
        shli    $87, $87, 16
        mpyu    $88, $86, $84
        a       $88, $88, $87                 # packet * depth (the packet past 16 bits)
        a       $88, $88, $71
        shli    $88, $88, 9
        a       $85, $85, $88
        il      $87, 512
        il      $88, 7
        il      $89, 0x20
        wrch    $MFC_LSA, $80
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $85
        wrch    $MFC_Size, $87
        wrch    $MFC_TagID, $88
        wrch    $MFC_Cmd, $89
        # the next level: its hits shaded, the level after's rays generated
        ai      $71, $71, 1
        stqd    $71, RF_STATE($70)
        stqd    ZERO, RF_CASTS($70)
        stqa    ZERO, rf_origin
        ori     $68, $81, 0
        lqd     $69, RF_REGS+16*69($70)
        hbrr    .Lrf_shade, shade_packet
.Lrf_shade:
        brsl    $0, shade_packet
        br      .Lrf_level

# ---- every level shaded: blend from the deepest up, a + r (b - a) + 0.5 per 8-bit
# channel, where r is the weight of the level's ray (0: a as it is)
.Lrf_blend:
        lqd     $71, RF_STATE($70)            # the last level shaded
        il      $75, 255
        lqa     $76, rf_half
1:      brz     $71, .Lrf_put
        ai      $71, $71, -1
        shli    $72, $71, 8
        ila     $73, RF_COLOURS
        a       $73, $73, $72
        a       $73, $73, $70                 # level k's block; k + 1's at +256
        ila     $74, RF_WEIGHTS
        a       $74, $74, $72
        a       $74, $74, $70                 # its weights
        .irp    V, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15
        lqd     $77, 16*\V($73)
        lqd     $78, 256+16*\V($73)
        lqd     $79, 16*\V($74)
        il      $80, 255                      # alpha
        .irp    S, 24, 16, 8
        rotmi   $81, $77, -\S
        and     $81, $81, $75
        cuflt   $81, $81, 0
        rotmi   $82, $78, -\S
        and     $82, $82, $75
        cuflt   $82, $82, 0
        fs      $83, $82, $81
        fma     $83, $79, $83, $81
        fa      $83, $83, $76
        cfltu   $83, $83, 0
        shli    $83, $83, \S
        or      $80, $80, $83
        .endr
        stqd    $80, 16*\V($73)
        .endr
        br      1b

# ---- the packet's colours to ea_colour + packet * 256 (tag 6, which the frame's end
# waits for), the registers back
.Lrf_put:
        lqd     $0, RF_REGS($70)
        hbr     .Lrf_ret, $0
        lqd     $80, SH_BLOCK($66)
        rotqbyi $80, $80, 8                   # ea_colour
        lqd     $81, RF_REGS+16*69($70)
        shli    $81, $81, 8
        a       $80, $80, $81
        ila     $82, RF_COLOURS
        a       $82, $82, $70
        il      $83, 256
        il      $84, 6
        il      $85, 0x20
        wrch    $MFC_LSA, $82
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $80
        wrch    $MFC_Size, $83
        wrch    $MFC_TagID, $84
        wrch    $MFC_Cmd, $85
        stqa    ZERO, rf_hold
        lqa     $86, rf_saved
        brnz    $86, .Lrf_restore
.Lrf_ret:
        bi      $0
.Lrf_restore:
        stqa    ZERO, rf_saved
        ori     $126, $70, 0
        RF_EACH_REG lqd, $126
        br      .Lrf_ret

# the first call: the counters start at 0 and the table is fetched again
.Lrf_clear:
        ila     $72, RF_COUNTERS
        a       $72, $72, $70
        il      $73, 4 * 8
1:      stqd    ZERO, 0($72)
        ai      $72, $72, 16
        ai      $73, $73, -1
        brnz    $73, 1b
        stqd    ZERO, RF_FLAG($70)
        il      $72, -1
        stqa    $72, rf_ready
        br      .Lrf_start

# ---- the shading module's colour block (from .Lsh_done while rf_hold is set: $66 = the
# shading area, $115 = the block) to this level's; returns to $0 as .Lsh_done does
reflect_block:
        hbr     .Lrb_ret, $0
        ila     $71, REFLECT_AREA
        a       $71, $71, $66
        lqd     $72, RF_STATE($71)
        brnz    $72, 1f
        RF_WAIT 6, $73                        # level 0's: the packet before's put is out
1:      shli    $72, $72, 8
        ila     $73, RF_COLOURS
        a       $73, $73, $72
        a       $73, $73, $71
        .sched  pool=74-90,94-114 scratch=66-127
        .irp    Q, 0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 208, 224, 240
        lqd     %c\Q, \Q($115)
      ~ stqd    %c\Q, \Q($73)
        .endr
        lqd     %n, SH_STATS+SHS_PACKETS($66)
        ai      %n1, %n, 1
      ~ stqd    %n1, SH_STATS+SHS_PACKETS($66)
        .endsched
.Lrb_ret:
        bi      $0

# ---- once the i-set is built (shade_light.s's .Lsh_iset_done, brsl $127): a
# reflection's normals turned to face its rays, and unless the level is the last, the next
# level's rays. Keeps $0..$66, $91..$93, $97, $124; uses $67..$90, $94..$96, $98..$123,
# $125, $126.
reflect_iset:
        hbr     .Lri_ret, $127
        lqa     $67, rf_hold
        brz     $67, .Lri_ret
        ila     $68, REFLECT_AREA
        a       $68, $68, $66
        lqd     $69, RF_FLAG($68)
        lqa     $70, rf_refl
        ceq     $71, $69, $70
        brz     $71, .Lri_fetch               # (the first call: out of line)
.Lri_fetched:
        lqd     $69, RF_STATE($68)            # the level
        lqd     $70, SH_BLOCK+SHB_REFLECT($66) # the depth
        brnz    $69, .Lri_flip                # (a reflection's: out of line)
.Lri_gen:
        stqd    ZERO, RF_CASTS($68)
        ceq     $71, $69, $70
        brnz    $71, .Lri_ret                 # the last level casts no ray
        ila     $74, RF_TABLE
        a       $74, $74, $68
        # a packet whose hits are all on one material (or none) that does not reflect casts
        # no ray: one lookup instead of 64
        .sched  pool=67,70-73,75-85,95,96,98-123,125,126 scratch=66-127
        lqd     %m0, SH_MAT($66)
        shufb   %s, %m0, %m0, PAT0            # ray 0's material, splatted
        .irp    V, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15
        lqd     %m\V, SH_MAT+16*\V($66)
        ceq     %e\V, %m\V, %s
        .endr
        and     %a0, %e0, %e1
        and     %a1, %e2, %e3
        and     %a2, %e4, %e5
        and     %a3, %e6, %e7
        and     %a4, %e8, %e9
        and     %a5, %e10, %e11
        and     %a6, %e12, %e13
        and     %a7, %e14, %e15
        and     %b0, %a0, %a1
        and     %b1, %a2, %a3
        and     %b2, %a4, %a5
        and     %b3, %a6, %a7
        and     %c0, %b0, %b1
        and     %c1, %b2, %b3
        and     %d, %c0, %c1
        gb      %g, %d
        ceqi    %same, %g, 15                 # every ray on ray 0's material
        ceqi    %none, %m0, -1
        andc    %mi, %m0, %none
        shli    %off, %mi, 2
        lqx     %q, $74, %off
        rotqby  %w, %q, %off
        fcgt    %refl, %w, ZERO
        andc    %refl, %refl, %none           # ray 0's material reflects
        andc    $71, %same, %refl
        .endsched
        brz     $71, .Lri_gen_rays            # (RF_CASTS is 0: none to generate)
.Lri_ret:
        bi      $127

.Lri_gen_rays:
        ila     $86, RF_DX                    # the incoming directions: the level's
        a       $86, $86, $68                 # rays', or the primary rays'
        brnz    $69, 2f
        lqd     $86, RF_REGS+16*68($68)
2:      shli    $87, $69, 8
        ila     $71, RF_WEIGHTS
        a       $87, $87, $71
        a       $87, $87, $68                 # the level's weights
        lqa     $88, rf_offset
        il      $89, 0                        # minus the rays cast
        lqa     $90, rf_pair
        lqa     $94, rf_halves
        .irp    G, 0, 8
        .sched  pool=67,70-73,75-85,95,96,98-123,125,126 scratch=66-127
        .irp    J, 0, 1, 2, 3, 4, 5, 6, 7
        lqd     %mat\J, SH_MAT+16*(\G+\J)($66)
        ceqi    %miss\J, %mat\J, -1           # no hit
        andc    %m\J, %mat\J, %miss\J
        shli    %o0\J, %m\J, 2                # the reflectances' byte offsets
        lqx     %q0\J, $74, %o0\J
        rotqby  %w0\J, %q0\J, %o0\J
        rotqbyi %o1\J, %o0\J, 4
        lqx     %q1\J, $74, %o1\J
        rotqby  %w1\J, %q1\J, %o1\J
        rotqbyi %o2\J, %o0\J, 8
        lqx     %q2\J, $74, %o2\J
        rotqby  %w2\J, %q2\J, %o2\J
        rotqbyi %o3\J, %o0\J, 12
        lqx     %q3\J, $74, %o3\J
        rotqby  %w3\J, %q3\J, %o3\J
        shufb   %w01\J, %w0\J, %w1\J, $90
        shufb   %w23\J, %w2\J, %w3\J, $90
        shufb   %w\J, %w01\J, %w23\J, $94     # the rays' reflectances
        fcgt    %rf\J, %w\J, ZERO
        andc    %c1\J, %rf\J, %miss\J        # a hit that reflects
        lqd     %dx\J, 16*(\G+\J)($86)         # d
        lqd     %dy\J, 256+16*(\G+\J)($86)
        lqd     %dz\J, 512+16*(\G+\J)($86)
        lqd     %nx\J, SH_NX+16*(\G+\J)($66)   # N
        lqd     %ny\J, SH_NY+16*(\G+\J)($66)
        lqd     %nz\J, SH_NZ+16*(\G+\J)($66)
        lqd     %px\J, SH_PX+16*(\G+\J)($66)   # P
        lqd     %py\J, SH_PY+16*(\G+\J)($66)
        lqd     %pz\J, SH_PZ+16*(\G+\J)($66)
        fm      %a1\J, %nx\J, %nx\J            # N.N
        fma     %a2\J, %ny\J, %ny\J, %a1\J
        fma     %nn\J, %nz\J, %nz\J, %a2\J
        fm      %b1\J, %dx\J, %nx\J            # d.N
        fma     %b2\J, %dy\J, %ny\J, %b1\J
        fma     %dn\J, %dz\J, %nz\J, %b2\J
        frest   %y0\J, %nn\J                  # 1 / N.N, one Newton step
        fi      %y1\J, %nn\J, %y0\J
        fnms    %ye\J, %nn\J, %y1\J, ONE
        fma     %y\J, %ye\J, %y1\J, %y1\J
        fm      %k1\J, %dn\J, %y\J
        fa      %k\J, %k1\J, %k1\J             # k = 2 d.N / N.N
        fnms    %rx\J, %nx\J, %k\J, %dx\J       # R = d - k N
        fnms    %ry\J, %ny\J, %k\J, %dy\J
        fnms    %rz\J, %nz\J, %k\J, %dz\J
        fcgt    %nz0\J, %nn\J, ZERO
        and     %c\J, %c1\J, %nz0\J            # (a zero normal reflects nothing)
        fma     %ox\J, %rx\J, $88, %px\J         # from P + REFLECT_OFFSET R
        fma     %oy\J, %ry\J, $88, %py\J
        fma     %oz\J, %rz\J, $88, %pz\J
        stqd    %ox\J, RF_OX+16*(\G+\J)($68)
        stqd    %oy\J, RF_OX+256+16*(\G+\J)($68)
        stqd    %oz\J, RF_OX+512+16*(\G+\J)($68)
        stqd    %rx\J, RF_DX+16*(\G+\J)($68)
        stqd    %ry\J, RF_DX+256+16*(\G+\J)($68)
        stqd    %rz\J, RF_DX+512+16*(\G+\J)($68)
        stqd    %c\J, RF_CAST+16*(\G+\J)($68)
        and     %ww\J, %w\J, %c\J
        stqd    %ww\J, 16*(\G+\J)($87)
        a       $89, $89, %c\J
        .endr
        .endsched
        .endr
        rotqbyi $71, $89, 8
        a       $89, $89, $71
        rotqbyi $71, $89, 4
        a       $89, $89, $71
        sf      $89, $89, ZERO
        stqd    $89, RF_CASTS($68)
        br      .Lri_ret

# the first call: the reflectance table
.Lri_fetch:
        lqd     $72, SH_BLOCK+SHB_REFLECT($66)
        rotqbyi $72, $72, 4
        ila     $73, RF_TABLE
        a       $73, $73, $68
        il      $74, 4 * RF_MATERIALS
        SH_GET  $73, $72, $74, $75
        stqd    $70, RF_FLAG($68)
        br      .Lri_fetched

.Lri_flip:
        # a reflection: N faces its ray R where dot(N, R) < 0
        .irp    G, 0, 8
        .sched  pool=71-90,94-96,98-123,125,126 scratch=66-127
        .irp    J, 0, 1, 2, 3, 4, 5, 6, 7
        lqd     %nx\J, SH_NX+16*(\G+\J)($66)
        lqd     %ny\J, SH_NY+16*(\G+\J)($66)
        lqd     %nz\J, SH_NZ+16*(\G+\J)($66)
        lqd     %rx\J, RF_DX+16*(\G+\J)($68)
        lqd     %ry\J, RF_DX+256+16*(\G+\J)($68)
        lqd     %rz\J, RF_DX+512+16*(\G+\J)($68)
        fm      %e1\J, %nx\J, %rx\J
        fma     %e2\J, %ny\J, %ry\J, %e1\J
        fma     %e\J, %nz\J, %rz\J, %e2\J
        fcgt    %f1\J, %e\J, ZERO
        and     %f\J, %f1\J, SIGNS
        xor     %ox\J, %nx\J, %f\J
        xor     %oy\J, %ny\J, %f\J
        xor     %oz\J, %nz\J, %f\J
        stqd    %ox\J, SH_NX+16*(\G+\J)($66)
        stqd    %oy\J, SH_NY+16*(\G+\J)($66)
        stqd    %oz\J, SH_NZ+16*(\G+\J)($66)
        .endr
        .endsched
        .endr
        br      .Lri_gen
