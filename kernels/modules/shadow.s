# shadow.s — shadow rays (paper section 7): per light, one 8x8 shadow packet from the light
# toward the packet's 64 hit points, traced by the primary rays' traversal (traverse.s,
# triangle.s) as an occlusion query; the result is the light's visibility masks (SH_VIS).
#
# `brsl $127, shadow_rays` from shade.s once the i-set holds the hit points (SH_PX..PZ),
# the eye-facing normals (SH_NX..NZ) and the materials (SH_MAT, -1: no hit), with $66 = the
# shading area. Keeps $0..$65 but the statistics ones (the traversal counts the shadow
# packets' work as it counts the primary packets'), and of $66..$127 those shade.s reads
# after the call: $66, $91..$93, $97, $101..$103, $105; returns to $127. Only the registers the
# traversal changes are saved and restored (the frame's constants it only reads). Does
# nothing unless the shading block's mode is SHADE_SHADOWS.
#
# The statistics are counted on, the frame's constants read, the packet registers saved
# and restored.
# Registers (tests/src/lib.rs's module harness checks them):
#   in:       $66 $127 ZERO ONE BIG NBIG PAT0..PAT3 NEGODD ROOTST S_TRIS S_CULLED S_TLOOK S_STEPS M1V EEV
#   out:      S_TRIS S_CULLED S_TLOOK S_STEPS M1V EEV
#   clobbers: $67..$90 $94..$96 $98..$100 $104 $106..$126
#
# A shadow ray starts AT THE LIGHT Lp with direction d = P - Lp and finds no triangle with
# 0 < s < 1 - SHADOW_EPSILON (loader/src/shading.rs): the packet's rays share the origin,
# so the traversal's interval-arithmetic frustum (here from the range of 1/d over the cast
# rays) and first-active-ray tests work as for primary rays. A ray is cast only where the
# shading needs it: a hit whose normal faces the light (the same c = dot(N, Lp - P) > 0
# shade.s computes); the others start with t = -1, which no box or triangle test accepts.
# The leaves' triangle culling by the packet's corner rays is switched off (corner rays
# d, -d, d, -d: some corner is always in front, never all outside an edge), since the
# shadow rays toward scattered hit points lie in no frustum of four packet rays. (A cone
# of four rays around the cast rays, a box across the first cast ray's largest axis, was
# tried: it culled under 2% of the conference's triangle tests and cost more cycles than
# it saved.)
#
# The traversal runs as with one packet context (blocking misses, the one-context miss
# handlers) whatever the SHT count, in a packet context of its own (SHADOW_CTX), so the
# suspended primary packets keep theirs. It ends at packet_done (output.s), which comes
# here while sv_trace is set. With --shadow-early on, sv_early makes every leaf (triangle.s,
# tri_next) deactivate the rays it occluded (t = -1) and end the packet once no ray is left;
# off, the packet is traced to the end as a nearest-hit query within the limit (the paper).
# A ray is visible when no triangle was recorded for it (its id is still -1).

# The shadow area (SHADOW_AREA, loader::kernel_abi::ShadowArea: SV_* in layout.inc):
# the shadow rays cast, the light being traced, the five miss-handler words of vars
# saved, the registers (one quadword each), the shadow packets' context.
        .if     SH_PY - SH_PX != 256 || SH_PZ - SH_PY != 256 || SH_NY - SH_NX != 256 || SH_NZ - SH_NY != 256
        .error  "shadow.s reads the i-set's x, y, z arrays 256 bytes apart"
        .endif

        .text
        .align  4
sv_trace:       .long 0, 0, 0, 0        # all ones while a shadow packet is traced
sv_early:       .long 0, 0, 0, 0        # ... and its leaves deactivate occluded rays
sv_tmp:         .long 0, 0, 0, 0
sv_ready:       .long 0, 0, 0, 0        # all ones once the counter is cleared
sv_corner_x:    .float 1.0, -1.0, 1.0, -1.0
sv_corner_y:    .float 0.375, -0.375, 0.375, -0.375
sv_corner_z:    .float 0.6875, -0.6875, 0.6875, -0.6875
sv_word2:       .long 0, 0, -1, 0
sv_tag:         .long SHADOW_TAG, 1 << SHADOW_TAG, 0, 0
sv_limit:       .long SHADOW_LIMIT_BITS, SHADOW_LIMIT_BITS, SHADOW_LIMIT_BITS, SHADOW_LIMIT_BITS
sv_minus1:      .float -1.0, -1.0, -1.0, -1.0

# the registers a shadow packet changes and its caller keeps, restored at the end: the
# context and the packet's own of regs.inc (RAYS, ORIG, OR1X..OR1Z, OBX..OBZ, the origin
# splats, STKBASE, NEGTAB, $43..$65), the link, and shade.s's (above). Not the frame's
# constants (the traversal only reads them) nor the statistics.
        .macro  SV_EACH_REG op, base
        .irp    R, 0, 1, 6, 11, 25, 27, 28, 29, 33, 34, 35, 39, 40, 42, 43, 44, 45, 46, 47, 48, 49, 50, 51, 52, 53, 54
        \op     $\R, SV_REGS+16*\R(\base)
        .endr
        .irp    R, 55, 56, 57, 58, 59, 60, 61, 62, 63, 64, 65, 66, 91, 92, 93, 97, 101, 102, 103
        \op     $\R, SV_REGS+16*\R(\base)
        .endr
        \op     $105, SV_REGS+16*105(\base)
        .endm

# the smallest lane of \lo and the largest of \hi, in every lane ($94, $95: scratch)
        .macro  SV_RANGE lo, hi
        .irp    ROT, 8, 4
        rotqbyi $94, \lo, \ROT
        fcgt    $95, \lo, $94
        selb    \lo, \lo, $94, $95
        rotqbyi $94, \hi, \ROT
        fcgt    $95, $94, \hi
        selb    \hi, \hi, $94, $95
        .endr
        .endm

# $rt = the shading area (from params), $sb = the shadow area
        .macro  SV_AREAS rt, sb
        ila     \sb, params
        lqd     \rt, PARAM_SHADING_QUAD(\sb)
        rotqbyi \rt, \rt, PARAM_SHADING_ROT + 4
        ila     \sb, SHADOW_AREA
        a       \sb, \sb, \rt
        .endm

        .align  3
shadow_rays:
        hbr     2f, $127                      # (eight instructions to its branch)
        stqa    $126, sv_tmp
        lqd     $126, SH_BLOCK+SHB_MODE($66)
        ceqi    $126, $126, SHADE_SHADOWS
        brnz    $126, 1f
        lqa     $126, sv_tmp                  # not --shade shadows: every light visible
        nop
        lnop
2:      bi      $127
1:      ila     $126, SHADOW_AREA
        a       $126, $126, $66
        SV_EACH_REG stqd, $126
        stqd    $127, SV_REGS+16*127($126)
        ori     $68, $126, 0
        # the one-context miss handlers while the shadow packets run
        .irp    W, 0, 1, 2, 3
        lqa     $70, vars+V_BMISSH+16*\W      # V_BMISSH, V_BFETCH, V_PFMISS, V_PFFETCH
        stqd    $70, SV_HANDLERS+16*\W($68)
        .endr
        lqa     $70, vars+V_NCTX1
        stqd    $70, SV_HANDLERS+16*4($68)
        lqa     $71, vars+V_ASSOC4
        il      $72, -1
        stqa    $72, vars+V_NCTX1
        ila     $72, .Lb_one_fetch
        stqa    $72, vars+V_BFETCH
        ila     $72, .Lpf_one_evict
        stqa    $72, vars+V_PFFETCH
        ila     $72, bvh_miss_one
        ila     $73, bvh_miss_ways
        selb    BMISSH, $72, $73, $71
        stqa    BMISSH, vars+V_BMISSH
        ila     $72, .Lpf_one
        ila     $73, .Lpf_ways
        selb    $72, $72, $73, $71
        stqa    $72, vars+V_PFMISS
        # the shadow packets' context
        ila     $72, SHADOW_CTX
        a       RAYS, $66, $72
        ai      NEGTAB, RAYS, CTX_NEGTAB
        ila     $72, CTX_STACK
        a       STKBASE, RAYS, $72
        lqa     $72, sv_tag
        stqd    $72, CTX_TAG(RAYS)
        lqa     $72, sv_corner_x
        stqd    $72, CTX_CORNERS(RAYS)
        lqa     $72, sv_corner_y
        stqd    $72, CTX_CORNERS+16(RAYS)
        lqa     $72, sv_corner_z
        stqd    $72, CTX_CORNERS+32(RAYS)
        stqd    ZERO, SV_LIGHT($68)
        lqa     $72, sv_ready                 # the first call clears the counter
        brz     $72, .Lsv_clear               # (out of line: the branch not taken, not missed)

# ---- the next light: generate its shadow packet and trace it
.Lsv_light:
        SV_AREAS $66, $68
        lqd     $69, SV_LIGHT($68)
        lqd     $70, SH_BLOCK($66)
        rotqbyi $70, $70, SHB_LIGHT_COUNT
        ceq     $70, $69, $70
        brnz    $70, .Lsv_end
        # the light: its position as the packet's origin, splatted
        shli    $70, $69, 5
        a       $70, $70, $66
        lqd     ORIG, SH_BLOCK+SHB_LIGHTS($70)  # (x, y, z, 0)
        shufb   OXS, ORIG, ORIG, PAT0
        shufb   OYS, ORIG, ORIG, PAT1
        shufb   OZS, ORIG, ORIG, PAT2
        lqa     $103, sv_limit
        lqa     $104, sv_minus1
        il      $105, -1
        ori     $106, BIG, 0                  # the cast rays' smallest and largest 1/d
        ori     $107, BIG, 0
        ori     $108, BIG, 0
        ori     $109, NBIG, 0
        ori     $110, NBIG, 0
        ori     $111, NBIG, 0
        il      $112, 0                       # minus the rays cast, per lane
        # (scheduled into even/odd pairs: the 16 vectors of the i-set, unrolled, in two
        # blocks of 8: in one block of 16 the scheduler, ranking by critical path, loads
        # every vector first, fills the pool and then waits on it: 1110 cycles, not ~800)
        .irp    G, 0, 8
        .sched  pool=69-102,113-127 scratch=66-127
        .irp    J, 0, 1, 2, 3, 4, 5, 6, 7
        lqd     %mat\J, SH_MAT+16*(\G+\J)($66)
        il      %c\J, 0                       # L = light - P and c = dot(N, L), as shade.s
        .irp    K, 0, 1, 2                    # (fma onto +0 rounds as shade.s's first fm)
        lqd     %p\J\K, SH_PX+256*\K+16*(\G+\J)($66)
        lqd     %n\J\K, SH_NX+256*\K+16*(\G+\J)($66)
        fs      %l\J\K, (OXS+\K), %p\J\K
        fma     %c\J, %n\J\K, %l\J\K, %c\J
        .endr
        fcgt    %lit\J, %c\J, ZERO
        ceqi    %miss\J, %mat\J, -1
        andc    %cast\J, %lit\J, %miss\J       # cast: a hit facing the light
        .irp    K, 0, 1, 2
        fs      %d\J\K, %p\J\K, (OXS+\K)       # d = P - light
        frest   %y\J\K, %d\J\K                # 1/d, one Newton step
        fi      %y\J\K, %d\J\K, %y\J\K
        fnms    %e\J\K, %d\J\K, %y\J\K, ONE
        fma     %r\J\K, %e\J\K, %y\J\K, %y\J\K
        selb    %lo\J\K, BIG, %r\J\K, %cast\J  # the range of the cast rays' 1/d
        fcgt    %ml\J\K, (106+\K), %lo\J\K
        selb    (106+\K), (106+\K), %lo\J\K, %ml\J\K
        selb    %hi\J\K, NBIG, %r\J\K, %cast\J
        fcgt    %mh\J\K, %hi\J\K, (109+\K)
        selb    (109+\K), (109+\K), %hi\J\K, %mh\J\K
      ~ stqd    %d\J\K, CTX_RAY_DX+256*\K+16*(\G+\J)(RAYS)
      ~ stqd    %r\J\K, CTX_RAY_RX+256*\K+16*(\G+\J)(RAYS)
        .endr
        selb    %t\J, $104, $103, %cast\J       # t: the limit, or -1 (not cast)
        a       $112, $112, %cast\J
      ~ stqd    %t\J, CTX_RAY_T+16*(\G+\J)(RAYS)
      ~ stqd    $105, CTX_RAY_ID+16*(\G+\J)(RAYS)
        .endr
        .endsched
        .endr
        # the rays cast: counted; none (or an empty scene) leaves the light visible
        rotqbyi $94, $112, 8
        a       $112, $112, $94
        rotqbyi $94, $112, 4
        a       $112, $112, $94
        lqd     $94, SV_RAYS($68)
        sf      $94, $112, $94
        stqd    $94, SV_RAYS($68)
        lqa     $95, vars+V_EMPTY
        ceqi    $94, $112, 0
        or      $94, $94, $95
        brnz    $94, shadow_done
        # the frustum (raygen.s's packet setup, with the cast rays' range of 1/d)
        lqa     $113, k_eps
        lqa     $114, k_eps20
        lqa     $115, k_abs
        .irp    K, 0, 1, 2
        SV_RANGE (106+\K), (109+\K)
        fcgt    $94, ZERO, (106+\K)           # directions of both signs: no bound
        fcgt    $95, ZERO, (109+\K)
        andc    $96, $94, $95
        fm      $97, (106+\K), $113
        fm      $98, (109+\K), $113
        andc    (\K+PAX), $97, $96
        andc    (\K+PBX), $98, $96
        and     $99, NBIG, $96
        fm      $100, (\K+OXS), (\K+PAX)
        and     $101, $100, $115
        fma     $100, $101, $114, $100
        fs      (\K+OAX), $99, $100
        fm      $100, (\K+OXS), (\K+PBX)
        and     $101, $100, $115
        fma     $100, $101, $114, $100
        fs      (\K+OBX), $99, $100
        .endr
        lqa     $94, k_oddmask
        and     F2, $103, $94
        xor     F2, F2, NEGODD                # (0, -limit, 0, -limit)
        # the first cast ray, and the root with it
        il      $67, 0
1:      a       $93, RAYS, $67
        lqd     $92, CTX_RAY_T($93)
        fcgt    $94, $92, ZERO
        gb      $95, $94
        ai      $67, $67, 16
        brz     $95, 1b
        hbrr    .Lsv_first_br, set_first
        clz     $95, $95                      # 4 lanes: the first = clz - 28
        rotmi   $94, $67, -2
        a       $95, $95, $94
        ai      $95, $95, -32                 # (less the 4 rays $67 has moved on)
        shufb   FIRST, $95, $95, PAT0
        lqa     $94, sv_word2
        selb    CUR, ROOTST, FIRST, $94
.Lsv_first_br:
        brsl    $0, set_first
        hbrr    .Lsv_trav_br, trav
        ori     STK, STKBASE, 0
        lqa     BMISSH, vars+V_BMISSH         # (a leaf's ray loop uses the register)
        il      $94, -1
        stqa    $94, sv_trace
        lqd     $94, SH_BLOCK+SHB_MODE($66)   # (mode, early, ...)
        rotqbyi $94, $94, 4
        ceqi    $94, $94, 0
        nor     $94, $94, $94
        stqa    $94, sv_early
.Lsv_trav_br:
        br      trav

# ---- the shadow packet is done (packet_done comes here while sv_trace is set): the
# light's visibility, then the next light
shadow_done:
        stqa    ZERO, sv_trace
        stqa    ZERO, sv_early
        SV_AREAS $66, $68
        lqd     $69, SV_LIGHT($68)
        shli    $70, $69, 8
        ila     $71, SH_VIS
        a       $70, $70, $71
        a       $70, $70, $66                 # the light's masks
        .sched  pool=71-99 scratch=66-127
        .irp    V, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15
        lqd     %id\V, CTX_RAY_ID+16*\V(RAYS)
        ceqi    %vis\V, %id\V, -1              # nothing recorded: visible
      ~ stqd    %vis\V, 16*\V($70)
        .endr
        .endsched
        ai      $69, $69, 1
        stqd    $69, SV_LIGHT($68)
        lqd     $70, SH_BLOCK($66)
        rotqbyi $70, $70, SHB_LIGHT_COUNT
        ceq     $70, $69, $70
        brz     $70, .Lsv_light               # another light (with one, not taken: no miss)

# ---- every light done: the miss handlers and the registers back
.Lsv_end:
        .irp    W, 0, 1, 2, 3
        lqd     $70, SV_HANDLERS+16*\W($68)
        stqa    $70, vars+V_BMISSH+16*\W
        .endr
        lqd     $70, SV_HANDLERS+16*4($68)
        stqa    $70, vars+V_NCTX1
        ori     $126, $68, 0
        lqd     $127, SV_REGS+16*127($126)
        hbr     .Lsv_ret, $127
        SV_EACH_REG lqd, $126
.Lsv_ret:
        bi      $127

# the first call: the shadow-ray counter starts at 0
.Lsv_clear:
        stqd    ZERO, SV_RAYS($68)
        il      $72, -1
        stqa    $72, sv_ready
        br      .Lsv_light

# ---- --shadow-early on, after each leaf (triangle.s): the rays it occluded stop (t = -1),
# and the packet ends once none is left
shadow_leaf:
        .sched  pool=66-127 scratch=66-127
        lqa     %m1, sv_minus1
        .irp    V, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15
        lqd     %id\V, CTX_RAY_ID+16*\V(RAYS)
        lqd     %t\V, CTX_RAY_T+16*\V(RAYS)
        ceqi    %vis\V, %id\V, -1
        selb    %s\V, %m1, %t\V, %vis\V
      ~ stqd    %s\V, CTX_RAY_T+16*\V(RAYS)
        fcgt    %l\V, %s\V, ZERO
        .endr
        or      %a0, %l0, %l1
        or      %a2, %l2, %l3
        or      %a4, %l4, %l5
        or      %a6, %l6, %l7
        or      %a8, %l8, %l9
        or      %a10, %l10, %l11
        or      %a12, %l12, %l13
        or      %a14, %l14, %l15
        or      %b0, %a0, %a2
        or      %b1, %a4, %a6
        or      %b2, %a8, %a10
        or      %b3, %a12, %a14
        or      %c0, %b0, %b1
        or      %c1, %b2, %b3
        or      %d, %c0, %c1
        gb      %g, %d
      ! brz     %g, packet_done
      ! br      .Lleaf_refresh
        .endsched
