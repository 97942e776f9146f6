# triangle.s — a leaf: the triangle test of the packet's active rays.
#
# A leaf fetches its missing triangles with back-to-back DMAs and one wait (misses go to
# modules/tri_cache.s), culls each triangle against the packet's corner rays, and tests
# the active rays (from the first active ray's group of 16 on) four vectors per pass with
# Wald's projection test, keeping per ray the nearest t, the triangle id and the cosine
# numerator for shading. When the leaf is done it refreshes the packet's largest t for
# the IA exit bound and pops the next traversal state (or finishes the packet).

        .text
# ---- leaf: test the active rays against each triangle of the leaf
leaf:
        .ifdef  EXT_MULTIHINT                 # (multihint) the prefetch pass as the last
        lqa     $74, pfpass                   # leaf's ended (pfpass, leaf_probe_m)
        .endif
        lqa     $80, vars+V_LEAVES
        ai      $80, $80, 1
        stqa    $80, vars+V_LEAVES
        # a new visit: what the staging slots hold is from an older leaf
        il      $86, -1
        .ifdef  EXT_MULTIHINT
        hbr     .Lleaf_pass, $74
        .endif
        .irp    J, 0, 1, 2, 3, 4, 5, 6, 7
        stqd    $86, CTX_STAGE_TAGS+\J*16(RAYS)
        .endr
        .ifdef  EXT_MULTIHINT
.Lleaf_pass:
        bi      $74                           # (leaf_probe, the next, or leaf_probe_m)
        .endif
leaf_probe:                                   # (a suspended leaf resumes here)
        ori     $66, CUR, 0                   # first triangle
        rotqbyi $67, CUR, 4
        rotmi   $67, $67, -6                  # count (meta << 4 >> 2 ... see bvh_miss)
        # bring every missing triangle of the leaf in with one wait: the DMAs queue back
        # to back, so a leaf pays the memory latency once (or once per suspension)
        ori     $76, $66, 0
        ori     $77, $67, 0
        il      $78, 0                        # any miss
        il      $79, 64
        lqa     $75, vars+V_PFMISS            # the miss handler for the configuration
        hbrr    .Lpf_br, .Lpf
.Lpf:   and     $80, $76, TMASK
        shli    $81, $80, 4
        lqx     $82, TTAGS, $81
        ceq     $83, $82, $76
        biz     $83, $75                      # hits fall through
.Lpf_next:
        ai      $76, $76, 1
        ai      $77, $77, -1
.Lpf_br:
        brnz    $77, .Lpf
.Lpf_done:
        .ifdef  EXT_MULTIHINT                 # (the last triangle was in the cache: the
        ila     $86, leaf_probe               # next leaf's pass predicts hits)
        stqa    $86, pfpass
        .endif
        brz     $78, leaf_cull
        lqa     $86, vars+V_NCTX1
        brz     $86, .Lpf_suspend
        lqd     $86, CTX_TAG(RAYS)
        rotqbyi $87, $86, 4
        il      $86, 2
        wrch    $MFC_WrTagMask, $87
        wrch    $MFC_WrTagUpdate, $86
        rdch    $86, $MFC_RdTagStat

# One triangle of the cull pass: its tag check, its plane rows, the origin in its
# (k, u, v) order, and the corner offsets of its projection axes (%ck, %cu, %cv).
        .macro  CULL_RECORD T
        ai      %tri\T, $76, \T
        and     %ln\T, %tri\T, TMASK
        shli    %lt\T, %ln\T, 4
        lqx     %tag\T, TTAGS, %lt\T
        shli    %ld\T, %ln\T, 6
        a       %rec\T, %ld\T, TDATA
        ceq     %th\T, %tag\T, %tri\T
        lqd     %q0\T, TRI_N_U(%rec\T)         # (n_u, n_v, n_d, k)
        lqd     %q1\T, TRI_B_NU(%rec\T)        # (b_nu, b_nv, b_d, -)
        lqd     %q2\T, TRI_C_NU(%rec\T)        # (c_nu, c_nv, c_d, -)
        rotqbyi %k\T, %q0\T, 12
        shli    %k16\T, %k\T, 4
        lqx     %ax\T, $80, %k16\T             # (k, u, v) array offsets
        lqx     %kp\T, $81, %k16\T
        shufb   %okuv\T, ORIG, ORIG, %kp\T     # origin in (k, u, v) order
        shufb   %nu\T, %q0\T, %q0\T, PAT0
        shufb   %nv\T, %q0\T, %q0\T, PAT1
        shufb   %nd\T, %q0\T, %q0\T, PAT2
        shufb   %bnu\T, %q1\T, %q1\T, PAT0
        shufb   %bnv\T, %q1\T, %q1\T, PAT1
        shufb   %bd\T, %q1\T, %q1\T, PAT2
        shufb   %cnu\T, %q2\T, %q2\T, PAT0
        shufb   %cnv\T, %q2\T, %q2\T, PAT1
        shufb   %cd\T, %q2\T, %q2\T, PAT2
        shufb   %ok\T, %okuv\T, %okuv\T, PAT0
        shufb   %ou\T, %okuv\T, %okuv\T, PAT1
        shufb   %ov\T, %okuv\T, %okuv\T, PAT2
        fs      %nm1\T, %nd\T, %ok\T
        fnms    %nm2\T, %nu\T, %ou\T, %nm1\T
        fnms    %num\T, %nv\T, %ov\T, %nm2\T   # n_d - o_k - n_u o_u - n_v o_v
        rotqbyi %axu\T, %ax\T, 4
        rotqbyi %axv\T, %ax\T, 8
        rotmi   %ck\T, %ax\T, -4
        rotmi   %cu\T, %axu\T, -4
        rotmi   %cv\T, %axv\T, -4
        .endm

# ---- the leaf's corner-ray frustum cull, two triangles a pass, before any is tested: a
# triangle every corner ray (0, 7, 56, 63) misses on one side, or that lies behind them
# all, is culled. One triangle's test is a chain of ~90 cycles of latency (the record,
# its axis, the corners' n.d, a reciprocal, the barycentrics), so two run side by side;
# each result goes to the slot cullbuf + (triangle & 7) * 16 (a leaf's triangles are
# consecutive, at most 8), which the test loop reads. The records are in the cache after
# the prefetch pass; a line that holds another triangle (two of the leaf on one line)
# is not culled, and the test loop's lookup fetches it (tri_miss). Keeps $66, $67.
leaf_cull:
        ori     $76, $66, 0                   # the pass's first triangle
        ori     $77, $67, 0                   # triangles left
        ila     $78, cullbuf
        ai      $79, RAYS, CTX_CORNERS        # the corner rays' x, y, z
        ila     $80, k_axoff
        ila     $81, k_kuv
        .ifdef  EXT_MULTIHINT
        # (the four triangles' cull below: its constants, scheduled as one block)
        .sched  pool=82-127 scratch=66-127
        ila     $75, numbuf                   # (the test's numerator, kept for tri_loop)
        lqd     $79, CTX_TAG(RAYS)            # this context's directions, per axis
        ila     $74, gforms                   # (raygen.s: (x, y, z) of base, du, dv)
        ai      $79, $79, -CONTEXT_TAG0
        mpyi    $79, $79, 48
        a       $79, $79, $74
        ila     $74, k_grange
        lqd     $80, 16($79)                  # per column
        lqd     $81, 32($79)                  # per row
        lqd     $79, 0($79)                   # at column 0 row 0
        lqa     $72, k_ctol
        lqa     $73, k_c7
        lqa     $68, k_grow0
        shufb   $72, $72, $72, PAT1           # the edges' margin, 2^-8
        shufb   $69, $68, $68, PAT2           # 4.0 (group 2's first row)
        rotmi   $70, FIRST, -4                # the active groups: FIRST's and after
        shli    $70, $70, 4
        ila     $71, k_lanege
        lqx     $70, $71, $70
        gb      $70, $70
        shufb   $70, $70, $70, PAT0
        shufb   $71, $68, $68, PAT3           # 6.0 (group 3's)
        shufb   $68, $68, $68, PAT1           # 2.0 (group 1's)
        cgti    %gt4, $67, 4                  # (more than four triangles: one pass of
        ila     %a4, cull_pass                   # eight)
        ila     %a8, cull_pass8
        selb    %to, %a4, %a8, %gt4
        hbr     .Lcull_in, %to
.Lcull_in:
        bi      %to
        .endsched
        .endif
        .ifndef EXT_MULTIHINT
        .sched  pool=82-127 scratch=66-127
.Lcull:
        .irp    T, 0, 1
        CULL_RECORD \T
        lqx     %dk\T, $79, %ck\T              # corner d_k, d_u, d_v
        lqx     %du\T, $79, %cu\T
        lqx     %dv\T, $79, %cv\T
        fma     %dn1\T, %nu\T, %du\T, %dk\T
        fma     %den\T, %nv\T, %dv\T, %dn1\T   # den = n.d
        frest   %y\T, %den\T
        fi      %y1\T, %den\T, %y\T
        fnms    %e\T, %den\T, %y1\T, ONE
        fma     %r\T, %e\T, %y1\T, %y1\T
        fm      %t\T, %num\T, %r\T             # t
        fma     %hu\T, %t\T, %du\T, %ou\T      # hit u
        fma     %hv\T, %t\T, %dv\T, %ov\T      # hit v
        fma     %be1\T, %bnu\T, %hu\T, %bd\T
        fma     %be\T, %bnv\T, %hv\T, %be1\T   # beta
        fma     %ga1\T, %cnu\T, %hu\T, %cd\T
        fma     %ga\T, %cnv\T, %hv\T, %ga1\T   # gamma
        fa      %bg\T, %be\T, %ga\T
        fcgt    %fr\T, %t\T, ZERO              # in front
        fcgt    %o1\T, ZERO, %be\T
        fcgt    %o2\T, ZERO, %ga\T
        fcgt    %o3\T, %bg\T, ONE
        and     %o1f\T, %o1\T, %fr\T
        and     %o2f\T, %o2\T, %fr\T
        and     %o3f\T, %o3\T, %fr\T
        gb      %gf\T, %fr\T
        gb      %g1\T, %o1f\T
        gb      %g2\T, %o2f\T
        gb      %g3\T, %o3f\T
        ceqi    %bh\T, %gf\T, 0                # every corner behind
        ceqi    %x1\T, %g1\T, 15               # every corner outside one edge
        ceqi    %x2\T, %g2\T, 15
        ceqi    %x3\T, %g3\T, 15
        or      %c1\T, %bh\T, %x1\T
        or      %c2\T, %x2\T, %x3\T
        or      %cl\T, %c1\T, %c2\T
        and     %cv\T, %cl\T, %th\T             # another triangle's line: not culled
        andi    %sl\T, %tri\T, 7
        shli    %so\T, %sl\T, 4
      ~ stqx    %cv\T, $78, %so\T
        .ifdef  EXT_MULTIHINT
      ~ stqx    %num\T, $75, %so\T
        .endif
        .endr
        ai      $76, $76, 2
        ai      $77, $77, -2
        cgti    %more, $77, 0
        ila     %back, .Lcull                 # the branch hinted where it goes: another
        ila     %out, tri_loop                # pass or the test loop
        selb    %to, %out, %back, %more
        hbr     .Lcull_br, %to
.Lcull_br:
        bi      %to
        .endsched
        .else
# Four triangles of the cull below, from the pass's first + O, one per lane (names end in S)
        .macro  CULL_QUAD S, O
        .irp    T, 0, 1, 2, 3
        ai      %tri\T\()\S, $76, \T+\O
        and     %ln\T\()\S, %tri\T\()\S, TMASK
        shli    %lt\T\()\S, %ln\T\()\S, 4
        lqx     %tag\T\()\S, TTAGS, %lt\T\()\S
        shli    %ld\T\()\S, %ln\T\()\S, 6
        a       %rec\T\()\S, %ld\T\()\S, TDATA
        lqd     %q0\T\()\S, TRI_N_U(%rec\T\()\S)         # (n_u, n_v, n_d, k)
        lqd     %q1\T\()\S, TRI_B_NU(%rec\T\()\S)        # (b_nu, b_nv, b_d, -)
        lqd     %q2\T\()\S, TRI_C_NU(%rec\T\()\S)        # (c_nu, c_nv, c_d, -)
        .endr
        # lanes: the triangles
        shufb   %tg01\S, %tag0\S, %tag1\S, %plo
        shufb   %tg23\S, %tag2\S, %tag3\S, %plo
        shufb   %tags\S, %tg01\S, %tg23\S, %pa
        shufb   %t76\S, $76, $76, PAT0
        .if     \O
        a       %triv0\S, %t76\S, %idx
        ai      %triv\S, %triv0\S, \O
        .else
        a       %triv\S, %t76\S, %idx
        .endif
        ceq     %th\S, %tags\S, %triv\S              # not another triangle's line
        .irp    Q, 0, 1, 2
        shufb   %a01\Q\()\S, %q\Q\()0\S, %q\Q\()1\S, %plo
        shufb   %a23\Q\()\S, %q\Q\()2\S, %q\Q\()3\S, %plo
        shufb   %b01\Q\()\S, %q\Q\()0\S, %q\Q\()1\S, %phi
        shufb   %b23\Q\()\S, %q\Q\()2\S, %q\Q\()3\S, %phi
        shufb   %w0\Q\()\S, %a01\Q\()\S, %a23\Q\()\S, %pa
        shufb   %w1\Q\()\S, %a01\Q\()\S, %a23\Q\()\S, %pb
        shufb   %w2\Q\()\S, %b01\Q\()\S, %b23\Q\()\S, %pa
        .endr
        shufb   %kv\S, %b010\S, %b230\S, %pb         # k
        # each lane's axes k, u = k+1, v = k+2 (mod 3) as word-select patterns
        shli    %k4\S, %kv\S, 2
        ai      %u4a\S, %k4\S, 4
        ceqi    %uw\S, %u4a\S, 12
        andc    %u4\S, %u4a\S, %uw\S
        ai      %v4a\S, %u4\S, 4
        ceqi    %vw\S, %v4a\S, 12
        andc    %v4\S, %v4a\S, %vw\S
        shufb   %kr\S, %k4\S, %k4\S, %rep
        shufb   %ur\S, %u4\S, %u4\S, %rep
        shufb   %vr\S, %v4\S, %v4\S, %rep
        a       %pk\S, %kr\S, PAT0
        a       %pu\S, %ur\S, PAT0
        a       %pv\S, %vr\S, PAT0
        shufb   %ok\S, ORIG, ORIG, %pk\S           # origin in (k, u, v) order
        shufb   %ou\S, ORIG, ORIG, %pu\S
        shufb   %ov\S, ORIG, ORIG, %pv\S
        fs      %nn1\S, %w20\S, %ok\S
        fnms    %nn2\S, %w00\S, %ou\S, %nn1\S
        fnms    %num\S, %w10\S, %ov\S, %nn2\S          # n_d - o_k - n_u o_u - n_v o_v
        fma     %b1\S, %w01\S, %ou\S, %w21\S
        fma     %bo\S, %w11\S, %ov\S, %b1\S            # beta at the origin
        fma     %c1\S, %w02\S, %ou\S, %w22\S
        fma     %co\S, %w12\S, %ov\S, %c1\S
        and     %sn\S, %num\S, SIGNS
        xor     %anum\S, %num\S, %sn\S               # |num|: the forms below come out times its sign
        # per coefficient C (0: at column 0 row 0, 1: per column, 2: per row) of
        # n.d (d), beta n.d (b), gamma n.d (g), (1 - beta - gamma) n.d (a); signs by
        # num's, so that a ray in front has n.d > 0; each edge's plus a margin of 2^-8
        # of n.d (far beyond the test's 2^-20 and its rounding)
        .irp    C, 0, 1, 2
        shufb   %xk\C\()\S, (\C+79), (\C+79), %pk\S
        shufb   %xu\C\()\S, (\C+79), (\C+79), %pu\S
        shufb   %xv\C\()\S, (\C+79), (\C+79), %pv\S
        fma     %dn\C\()\S, %w00\S, %xu\C\()\S, %xk\C\()\S
        fma     %fdn\C\()\S, %w10\S, %xv\C\()\S, %dn\C\()\S     # n.d
        xor     %hd\C\()\S, %fdn\C\()\S, %sn\S              # (times num's sign, exactly)
        fm      %pb1\C\()\S, %w01\S, %xu\C\()\S
        fma     %pb\C\()\S, %w11\S, %xv\C\()\S, %pb1\C\()\S
        fm      %pg1\C\()\S, %w02\S, %xu\C\()\S
        fma     %pg\C\()\S, %w12\S, %xv\C\()\S, %pg1\C\()\S
        fm      %fb1\C\()\S, %bo\S, %hd\C\()\S
        fma     %fb\C\()\S, %anum\S, %pb\C\()\S, %fb1\C\()\S     # beta n.d = beta_o n.d + num (b_nu d_u + b_nv d_v)
        fm      %fg1\C\()\S, %co\S, %hd\C\()\S
        fma     %fg\C\()\S, %anum\S, %pg\C\()\S, %fg1\C\()\S
        fs      %fa1\C\()\S, %hd\C\()\S, %fb\C\()\S
        fs      %fa\C\()\S, %fa1\C\()\S, %fg\C\()\S
        fma     %hb\C\()\S, $72, %hd\C\()\S, %fb\C\()\S
        fma     %hg\C\()\S, $72, %hd\C\()\S, %fg\C\()\S
        fma     %ha\C\()\S, $72, %hd\C\()\S, %fa\C\()\S
        .endr
        # each one's largest over group g (columns 0..7, rows 2g, 2g+1):
        # v0 + max(0, 7 v_col) + max(0, v_row) + 2g v_row
        .irp    F, d, b, g, a
        fm      %w\F\()\S, %h\F\()1\S, $73
        fcgt    %pw\F\()\S, %w\F\()\S, ZERO
        and     %mw\F\()\S, %w\F\()\S, %pw\F\()\S
        fcgt    %pr\F\()\S, %h\F\()2\S, ZERO
        and     %mr\F\()\S, %h\F\()2\S, %pr\F\()\S
        fa      %k1\F\()\S, %h\F\()0\S, %mw\F\()\S
        fa      %m\F\()0\S, %k1\F\()\S, %mr\F\()\S
        fma     %m\F\()1\S, $68, %h\F\()2\S, %m\F\()0\S
        fma     %m\F\()2\S, $69, %h\F\()2\S, %m\F\()0\S
        fma     %m\F\()3\S, $71, %h\F\()2\S, %m\F\()0\S
        .endr
        # group g is kept (bit 3 - g) where some ray is in front and not every ray is
        # outside one edge
        .irp    G, 0, 1, 2, 3
        fcgt    %fr\G\()\S, %md\G\()\S, ZERO
        fcgt    %ob\G\()\S, ZERO, %mb\G\()\S
        fcgt    %og\G\()\S, ZERO, %mg\G\()\S
        fcgt    %oa\G\()\S, ZERO, %ma\G\()\S
        or      %o1\G\()\S, %ob\G\()\S, %og\G\()\S
        or      %o2\G\()\S, %o1\G\()\S, %oa\G\()\S
        andc    %kp\G\()\S, %fr\G\()\S, %o2\G\()\S
        andi    %bit\G\()\S, %kp\G\()\S, 8 >> \G
        .endr
        or      %m01\S, %bit0\S, %bit1\S
        or      %m23\S, %bit2\S, %bit3\S
        or      %m\S, %m01\S, %m23\S
        il      %all\S, 15
        selb    %mi\S, %all\S, %m\S, %th\S             # another triangle's line: every group
        and     %mact\S, %mi\S, $70                # of the active ones
        shli    %mo\S, %mact\S, 4
        andi    %sl\S, %triv\S, 7
        shli    %so\S, %sl\S, 4
        .irp    T, 0, 1, 2, 3
        rotqbyi %mo\T\()\S, %mo\S, 4*\T
        rotqbyi %so\T\()\S, %so\S, 4*\T
        lqx     %rg\T\()\S, $74, %mo\T\()\S
        shufb   %nm\T\()\S, %num\S, %num\S, PAT\T
      ~ stqx    %rg\T\()\S, $78, %so\T\()\S
      ~ stqx    %nm\T\()\S, $75, %so\T\()\S
        .endr
        ceqi    %cz\S, %mact\S, 0                 # culled: bit 3 - T of %gz
        gb      %gz\S, %cz\S
        .endm

# (multihint; needs no extension) the cull per group of 16 rays (two rows), four triangles
# a pass, one per lane: for rays from one origin, n.d, beta n.d and gamma n.d are linear in
# d, so affine in (column, row); with the test loop's arithmetic and a margin, a group is
# culled only where the test would miss every ray of it: the slot gets the range of groups
# left to test (k_grange: the first's and the last's offsets; none when every group is
# culled), which tri_loop and the test loop follow. Each lane's arithmetic is, op for op,
# that of one triangle done alone, so the verdicts do not depend on the lanes. A pass past
# the leaf's end fills the slots of triangles after it (no slot of the leaf's: at most 8)
        # Both passes' constants: a 4x4 transpose's patterns (k_plo, k_phi, k_pa, k_pb),
        # the lanes' numbers (k_idx) and each word's low byte made four (k_rep).
        .macro  CULL_CONSTANTS
        lqa     %plo, k_plo
        lqa     %phi, k_phi
        lqa     %pa, k_pa
        lqa     %pb, k_pb
        lqa     %idx, k_idx
        lqa     %rep, k_rep
        .endm
        .sched  pool=82-127 scratch=66-127
cull_pass:
        CULL_CONSTANTS
        CULL_QUAD a, 0
        shli    %cm, %gza, 28                 # (the culled ones, for .Ltri_hit's step)
        stqa    %cm, cullmask
        stqa    $76, cullbase
        ai      $76, $76, 4
        ai      $77, $77, -4
        cgti    %more, $77, 0
        ila     %back, cull_pass
        ila     %out, tri_loop
        selb    %to, %out, %back, %more
        hbr     .Lcull_br, %to
.Lcull_br:
        bi      %to
        .endsched
# a leaf of more than four triangles: all of them in one pass, two quads side by side
        .sched  pool=82-127 scratch=66-127
cull_pass8:
        CULL_CONSTANTS
        CULL_QUAD a, 0
        CULL_QUAD b, 4
        shli    %cma, %gza, 28
        shli    %cmb, %gzb, 24
        or      %cm, %cma, %cmb
        stqa    %cm, cullmask
        stqa    $76, cullbase
        hbrr    .Lcull_br8, tri_loop
.Lcull_br8:
        br      tri_loop
        .endsched
# (multihint; needs the extension) the prefetch pass of a leaf after one whose last
# triangle missed the cache: its tag check's branch to the miss handler is hinted taken,
# in an entry of its own beside the loop's and the handler's (a hit then costs the miss
# the fall-through costs in leaf_probe's pass). The handler comes back to .Lpf_m; with
# one context (.Lpf_one, .Lpf_ways) to leaf_probe's .Lpf_next, the same pass
leaf_probe_m:
        lqa     $75, vars+V_PFMISS            # the miss handler for the configuration
        ori     $66, CUR, 0                   # first triangle
        rotqbyi $67, CUR, 4
        rotmi   $67, $67, -6                  # count
        ori     $76, $66, 0
        hbr     .Lpf_m_miss, $75
        ori     $77, $67, 0
        il      $78, 0                        # any miss
        il      $79, 64
        hbrr    .Lpf_m_br, .Lpf_m
        hbrr    .Lpf_m_out, .Lpf_done
.Lpf_m: and     $80, $76, TMASK
        shli    $81, $80, 4
        lqx     $82, TTAGS, $81
        ceq     $83, $82, $76
.Lpf_m_miss:
        biz     $83, $75
        ai      $76, $76, 1
        ai      $77, $77, -1
.Lpf_m_br:
        brnz    $77, .Lpf_m
.Lpf_m_out:
        br      .Lpf_done
        .align  6                             # (not run: tri_loop where its block ends
        .rept   6                             # on ray_loop's line, whose .align 6 then
        nop                                   # pads nothing)
        .endr
        .endif
tri_loop:
        ai      S_TLOOK, S_TLOOK, 1
        and     $80, $66, TMASK
        andi    $100, $66, 7                  # the leaf's cull (leaf_cull)
        shli    $81, $80, 4
        shli    $100, $100, 4
        shli    $82, $80, 6
        lqx     $83, TTAGS, $81
        ila     $101, cullbuf
        lqx     $113, $101, $100
        a       $84, TDATA, $82
        ceq     $85, $83, $66
        sf      S_CULLED, $113, S_CULLED      # +1 when culled
        brnz    $113, tri_next
        brz     $85, tri_miss                 # hits fall through
        # (scheduled into even/odd pairs: the record's splats, the first active group's
        # offset)
        .sched  scratch=66-127
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
        shufb   $68, $86, $86, PAT0            # n_u
        shufb   $69, $86, $86, PAT1            # n_v
        shufb   $93, $86, $86, PAT2           # n_d
        shufb   $71, $87, $87, PAT0            # b_nu
        shufb   $72, $87, $87, PAT1            # b_nv
        shufb   $73, $87, $87, PAT2            # b_d
        shufb   $74, $88, $88, PAT0            # c_nu
        shufb   $75, $88, $88, PAT1            # c_nv
        shufb   $120, $88, $88, PAT2          # c_d
        shufb   $94, $92, $92, PAT0           # o_k
        shufb   $121, $92, $92, PAT1          # o_u
        shufb   $122, $92, $92, PAT2          # o_v
        .ifdef  EXT_MULTIHINT                 # (multihint; needs no extension) the cull
        ila     $114, numbuf                  # computed it, off this block's critical
        lqx     $70, $114, $100               # path (a test-loop miss: .Ltri_hit_m)
        .else
        fs      $70, $93, $94
        fnms    $70, $68, $121, $70
        fnms    $70, $69, $122, $70              # num = n_d - o_k - n_u o_u - n_v o_v
        .endif
        .ifndef SHADE                         # (the eye-light grey's n.d/|n|: unshaded)
        fm      $95, $68, $68
        fma     $95, $69, $69, $95
        fa      $95, $95, ONE
        frsqest $96, $95
        fi      $123, $95, $96                # 1/|n|, n = (1, n_u, n_v) in (k, u, v)
        .endif
        shufb   $124, $66, $66, PAT0          # triangle index
        ori     $97, RAYS, 0
        rotqbyi $98, $91, 4
        rotqbyi $99, $91, 8
        a       $125, $97, $91                # base of d_k
        a       $126, $97, $98                # d_u
        a       $127, $97, $99                # d_v
        ai      S_TRIS, S_TRIS, 1

        # the active rays, four vectors (16 rays) per pass, from FIRST's group on
        .ifdef  EXT_MULTIHINT                 # (from the first active group the cull
        ila     $115, cullbuf                 # keeps to the last, $112: leaf_cull)
        lqx     $116, $115, $100
        rotqbyi $119, $116, 4
        rotqbyi $112, $116, 8
        # the step to the next triangle the cull keeps (at most to the leaf's end), for
        # the test loop's last pass in $112's word 1: runs of culled triangles cost no
        # branch each; the ones it skips are counted as tri_loop counts them
        lqa     $102, cullmask
        lqa     $103, cullbase
        sf      $104, $103, $66
        ai      $104, $104, 1
        shl     $105, $102, $104              # the culled ones after this one, from bit 31
        nor     $105, $105, $105
        clz     $106, $105                    # culled ones in a row
        ai      $107, $106, 1
        cgt     $108, $107, $67
        selb    $118, $107, $67, $108
        ai      $109, $118, -1
        a       S_CULLED, S_CULLED, $109
        a       S_TLOOK, S_TLOOK, $109
        rotqbyi $110, $118, 12
        fsmbi   $111, 0x0f00
        selb    $112, $112, $110, $111        # (last, step, -, -)
        .else
        rotmi   $119, FIRST, -4
        shli    $119, $119, 6                 # byte offset of the first group
        .endif
        .endsched

        # the inside test admits barycentrics down to -2^-20 (and a sum up to 1 + 2^-20),
        # so a ray through the shared edge of two triangles hits one of them whatever
        # the truncating arithmetic makes of the edge; the nearer hit wins as usual
        lqa     $76, k_ntol
        lqa     $77, k_onetol
        # (scheduled into even/odd pairs from the 4-vector test: loads, den = n.d, t,
        # barycentrics, hit = t in (0, t_old) and inside, selb updates of t, id, n.d/|n|)
        .align  6                     # early in a fetch line: the loop refills no line while it runs
        .sched  pool=59,65,78-111,113-118 scratch=66-127
ray_loop:
        .ifdef  EXT_MULTIHINT
        ceq     %last, $119, $112             # the last pass: the leaf's next kept
        rotqbyi %step, $112, 4                # triangle ($112's word 1: .Ltri_hit)
        and     %inc, %last, %step
        .else
        ceqi    %last, $119, 192              # the last pass: the leaf's next triangle
        il      %one, 1
        and     %inc, %last, %one
        .endif
        # (tri_next's work, branch-free) and the branch hinted to the next triangle's
        a       $66, $66, %inc                # test or, after the leaf's last, to its
        sf      $67, %inc, $67                # end: no miss at the end of a test
        ceqi    %done, $67, 0
        ila     %back, ray_loop
        ila     %next, tri_loop
        ila     %end, .Lleaf_end
        selb    %out, %next, %end, %done
        selb    %to, %back, %out, %last
        hbr     .Lray_br, %to
        a       %tp, RAYS, $119
        lqx     %dk0, $125, $119
        lqx     %du0, $126, $119
        lqx     %dv0, $127, $119
        ai      $119, $119, 16
        fma     %den0, $68, %du0, %dk0
        fma     %den0, $69, %dv0, %den0
        frest   %y0, %den0
        fi      %y0, %den0, %y0
        fnms    %e0, %den0, %y0, ONE
        fma     %e0, %e0, %y0, %y0
        fm      %t0, $70, %e0
        fma     %du0, %t0, %du0, $121
        fma     %dv0, %t0, %dv0, $122
        fma     %be0, $71, %du0, $73
        fma     %ga0, $74, %du0, $120
        fma     %be0, $72, %dv0, %be0
        fma     %ga0, $75, %dv0, %ga0
        lqd     %to0, CTX_RAY_T+0(%tp)
        fa      %bg0, %be0, %ga0
        fcgt    %o10, $76, %be0
        fcgt    %o20, $76, %ga0
        fcgt    %o30, %bg0, $77
        fcgt    %cl0, %to0, %t0
        fcgt    %cl20, %t0, ZERO
        or      %o10, %o10, %o20
        and     %cl0, %cl0, %cl20
        or      %o10, %o10, %o30
        andc    %hit0, %cl0, %o10
        lqd     %io0, CTX_RAY_ID+0(%tp)
        selb    %to0, %to0, %t0, %hit0
        selb    %io0, %io0, $124, %hit0
      ~ stqd    %to0, CTX_RAY_T+0(%tp)
      ~ stqd    %io0, CTX_RAY_ID+0(%tp)
        .ifndef SHADE
        lqd     %no0, CTX_RAY_ND+0(%tp)
        fm      %nd0, %den0, $123
        selb    %no0, %no0, %nd0, %hit0
      ~ stqd    %no0, CTX_RAY_ND+0(%tp)
        .endif
        lqx     %dk1, $125, $119
        lqx     %du1, $126, $119
        lqx     %dv1, $127, $119
        ai      $119, $119, 16
        fma     %den1, $68, %du1, %dk1
        fma     %den1, $69, %dv1, %den1
        frest   %y1, %den1
        fi      %y1, %den1, %y1
        fnms    %e1, %den1, %y1, ONE
        fma     %e1, %e1, %y1, %y1
        fm      %t1, $70, %e1
        fma     %du1, %t1, %du1, $121
        fma     %dv1, %t1, %dv1, $122
        fma     %be1, $71, %du1, $73
        fma     %ga1, $74, %du1, $120
        fma     %be1, $72, %dv1, %be1
        fma     %ga1, $75, %dv1, %ga1
        lqd     %to1, CTX_RAY_T+16(%tp)
        fa      %bg1, %be1, %ga1
        fcgt    %o11, $76, %be1
        fcgt    %o21, $76, %ga1
        fcgt    %o31, %bg1, $77
        fcgt    %cl1, %to1, %t1
        fcgt    %cl21, %t1, ZERO
        or      %o11, %o11, %o21
        and     %cl1, %cl1, %cl21
        or      %o11, %o11, %o31
        andc    %hit1, %cl1, %o11
        lqd     %io1, CTX_RAY_ID+16(%tp)
        selb    %to1, %to1, %t1, %hit1
        selb    %io1, %io1, $124, %hit1
      ~ stqd    %to1, CTX_RAY_T+16(%tp)
      ~ stqd    %io1, CTX_RAY_ID+16(%tp)
        .ifndef SHADE
        lqd     %no1, CTX_RAY_ND+16(%tp)
        fm      %nd1, %den1, $123
        selb    %no1, %no1, %nd1, %hit1
      ~ stqd    %no1, CTX_RAY_ND+16(%tp)
        .endif
        lqx     %dk2, $125, $119
        lqx     %du2, $126, $119
        lqx     %dv2, $127, $119
        ai      $119, $119, 16
        fma     %den2, $68, %du2, %dk2
        fma     %den2, $69, %dv2, %den2
        frest   %y2, %den2
        fi      %y2, %den2, %y2
        fnms    %e2, %den2, %y2, ONE
        fma     %e2, %e2, %y2, %y2
        fm      %t2, $70, %e2
        fma     %du2, %t2, %du2, $121
        fma     %dv2, %t2, %dv2, $122
        fma     %be2, $71, %du2, $73
        fma     %ga2, $74, %du2, $120
        fma     %be2, $72, %dv2, %be2
        fma     %ga2, $75, %dv2, %ga2
        lqd     %to2, CTX_RAY_T+32(%tp)
        fa      %bg2, %be2, %ga2
        fcgt    %o12, $76, %be2
        fcgt    %o22, $76, %ga2
        fcgt    %o32, %bg2, $77
        fcgt    %cl2, %to2, %t2
        fcgt    %cl22, %t2, ZERO
        or      %o12, %o12, %o22
        and     %cl2, %cl2, %cl22
        or      %o12, %o12, %o32
        andc    %hit2, %cl2, %o12
        lqd     %io2, CTX_RAY_ID+32(%tp)
        selb    %to2, %to2, %t2, %hit2
        selb    %io2, %io2, $124, %hit2
      ~ stqd    %to2, CTX_RAY_T+32(%tp)
      ~ stqd    %io2, CTX_RAY_ID+32(%tp)
        .ifndef SHADE
        lqd     %no2, CTX_RAY_ND+32(%tp)
        fm      %nd2, %den2, $123
        selb    %no2, %no2, %nd2, %hit2
      ~ stqd    %no2, CTX_RAY_ND+32(%tp)
        .endif
        lqx     %dk3, $125, $119
        lqx     %du3, $126, $119
        lqx     %dv3, $127, $119
        ai      $119, $119, 16
        fma     %den3, $68, %du3, %dk3
        fma     %den3, $69, %dv3, %den3
        frest   %y3, %den3
        fi      %y3, %den3, %y3
        fnms    %e3, %den3, %y3, ONE
        fma     %e3, %e3, %y3, %y3
        fm      %t3, $70, %e3
        fma     %du3, %t3, %du3, $121
        fma     %dv3, %t3, %dv3, $122
        fma     %be3, $71, %du3, $73
        fma     %ga3, $74, %du3, $120
        fma     %be3, $72, %dv3, %be3
        fma     %ga3, $75, %dv3, %ga3
        lqd     %to3, CTX_RAY_T+48(%tp)
        fa      %bg3, %be3, %ga3
        fcgt    %o13, $76, %be3
        fcgt    %o23, $76, %ga3
        fcgt    %o33, %bg3, $77
        fcgt    %cl3, %to3, %t3
        fcgt    %cl23, %t3, ZERO
        or      %o13, %o13, %o23
        and     %cl3, %cl3, %cl23
        or      %o13, %o13, %o33
        andc    %hit3, %cl3, %o13
        lqd     %io3, CTX_RAY_ID+48(%tp)
        selb    %to3, %to3, %t3, %hit3
        selb    %io3, %io3, $124, %hit3
      ~ stqd    %to3, CTX_RAY_T+48(%tp)
      ~ stqd    %io3, CTX_RAY_ID+48(%tp)
        .ifndef SHADE
        lqd     %no3, CTX_RAY_ND+48(%tp)
        fm      %nd3, %den3, $123
        selb    %no3, %no3, %nd3, %hit3
      ~ stqd    %no3, CTX_RAY_ND+48(%tp)
        .endif
.Lray_br:
      ! bi      %to
        .endsched


        .ifdef  EXT_MULTIHINT
# a triangle fetched by the test loop's miss (tri_miss): the cull's numerator in its slot
# may be another triangle's (the line held that one), so it is computed here
.Ltri_hit_m:
        andi    $100, $66, 7
        shli    $100, $100, 4
        lqd     $86, TRI_N_U($84)
        rotqbyi $89, $86, 12
        shli    $89, $89, 4
        ila     $90, k_kuv
        lqx     $92, $90, $89
        shufb   $92, ORIG, ORIG, $92
        shufb   $68, $86, $86, PAT0
        shufb   $69, $86, $86, PAT1
        shufb   $93, $86, $86, PAT2
        shufb   $94, $92, $92, PAT0
        shufb   $121, $92, $92, PAT1
        shufb   $122, $92, $92, PAT2
        fs      $70, $93, $94
        fnms    $70, $68, $121, $70
        fnms    $70, $69, $122, $70
        ila     $114, numbuf
        stqx    $70, $114, $100
        br      .Ltri_hit
        .endif

tri_next:                                     # (a culled triangle)
        ai      $66, $66, 1
        ai      $67, $67, -1
        brnz    $67, tri_loop
.Lleaf_end:
        .ifdef  SHADE                         # --shadow-early on: occluded rays stop
        lqa     $80, sv_early                 # (modules/shadow.s)
        brnz    $80, shadow_leaf
.Lleaf_refresh:
        .endif
        # the packet's largest t shrinks as rays hit: refresh the IA exit bound
        hbrr    .Lpop_br, .Lnewcur            # (pop's way back to traversal)
        .irp    J, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15
        lqd     (\J+81), CTX_RAY_T+\J*16(RAYS)
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
        lqa     BMISSH, vars+V_BMISSH         # (the ray loop used the register)

# ---- pop: continue with the entry on top of the stack, or finish the packet
pop:
        ceq     $126, STK, STKBASE
        lqd     CUR, -16(STK)
        ai      STK, STK, -16
        brnz    $126, packet_done
.Lpop_br:
        br      .Lnewcur
