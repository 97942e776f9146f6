# shade_light.s — the shading module's lighting and output (modules/shade.s).
#
# Multi-pass shading: the first material still referenced in the i-set is looked up in
# the direct-mapped material cache, its diffuse shader (kd * (ambient + irradiance), to
# 8 bits) runs over all 16 intersection packets under the mask of its rays, and then
# clears their references; until none is left (the paper's 1-2 passes per packet). The
# irradiance, dot(N, L) / (|N| |L|) clamped, times the light's colour, summed over the
# lights (SH_VIS: per light, the rays' visibility masks), is computed in the same block
# as the colour: the first pass runs it once per light, adding to the sums (stored),
# the last light's run shading; a later pass runs it with a black light (adding exactly
# 0), shading from the stored sums. The pass that leaves no material ends the packet,
# whose colour block is put to ea_colour + packet * 256.
#
# Entered at .Lsh_iset_done with the i-set built, $66 = the area, $97 = the packet
# number, $124 = the fast path's counts (groups, same, triangle lookups); calls
# shadow_rays (modules/shadow.s), which keeps $66, $91..$93, $97, $101..$103, $105; a
# material cache miss goes out of line to .Lsh_mmiss (modules/shade_cache.s) and comes
# back to .Lsh_mhit with the line at $73. Returns to $0. With EXT_GATHER a run is one
# block of all 16 groups (SH_LIGHT_RUN; one channel for a grey first light) and a later
# pass is .Lsh_later_g (modules/shade_gather.s): the same values, other schedules.

        # the fast groups' counters (groups, same, triangle lookups) to SH_STATS
.Lsh_iset_done:
        .ifdef  EXT_GATHER                    # steps the fast path left: the batch
        lqa     $74, sh_gn                    # (modules/shade_gather.s)
        brnz    $74, .Lsh_gbatch
        .endif
        .ifdef  REFLECT                       # the reflection's normals, the next level's
        brsl    $127, reflect_iset            # rays (modules/reflect.s)
        .endif
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
        stqd    %w, SH_RUN_OUT($66)           # EA, tag, material cache EA, index mask
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
        lqd     %run, SH_RUN_OUT($66)
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
        .ifdef  EXT_GATHER                    # a later pass: from the stored sums
        brz     $84, .Lsh_later_g             # (modules/shade_gather.s)
        # One group's colour from its scaled channels (%rk\g, %gk\g, %bk\g; \g the
        # group's register suffix, \off its offset): converted, packed and written under
        # its shader's pattern, its rays marked shaded; the frame buffer's load waits on
        # \gate. The gather variant's runs and its later pass (shade_gather.s) share it.
        .macro  SH_COLOUR_OUT g, off, gate
        fma     %rs\g, %rk\g, $106, $126
        cfltu   %ru\g, %rs\g, 24
        fma     %gs\g, %gk\g, $106, $126
        cfltu   %gu\g, %gs\g, 24
        fma     %bs\g, %bk\g, $106, $126
        cfltu   %bu\g, %bs\g, 24
        shufb   %rg\g, %ru\g, %gu\g, $88
        shufb   %col\g, %rg\g, %bu\g, $89
        lqd     %o\g, \off($115) @after \gate
        shufb   %o2\g, %o\g, %col\g, %pat\g
      ~ stqd    %o2\g, \off($115)
        shufb   %mn\g, %m\g, %none, %pat\g
      ~ stqd    %mn\g, SH_MAT+\off($66)
        and     $86, $86, %mn\g
        .endm
        # The gather variant's run: the same values as .Lsh_shade_g's below, all 16
        # groups in one block (no loop: no pointer, counter or exit per 4 groups, and
        # the groups' chains overlap across the whole run). A group's loads wait for the
        # cosine of the group two before it (%cs\B: the groups of one parity share it),
        # which keeps the odd pipe from loading ahead until the pool is full and the
        # even pipe stalls. A group's two selects by its shader's rays are one pattern
        # (selb) and two shufb (the odd pipe idles here: lighting is even-pipe bound).
        # A grey light (r = g = b, bitwise) adding to no sums yet (the first light) gives
        # a grey irradiance: its run computes and adds one channel and stores it as all
        # three (the same bits: cs * l + 0 per channel), 4 even-pipe instructions a group
        # fewer; any other light takes the three channels.
        .macro  SH_LIGHT_RUN label, grey
        .sched  pool=67,69,76-82,84,90-105,107-114,116-120,127 scratch=66-127
\label:
        il      %none, -1
        lqa     %pkeep, sh_gsel               # bytes of a, of b (shufb)
        lqa     %ptake, sh_gsel+16
        .irp    A, 0, 32, 64, 96, 128, 160, 192, 224
        .irp    B, 0, 16
        lqd     %nx\A\()_\B, SH_NX+\A+\B($66) @after %cs\B
        lqd     %ny\A\()_\B, SH_NY+\A+\B($66) @after %cs\B
        lqd     %nz\A\()_\B, SH_NZ+\A+\B($66) @after %cs\B
        lqd     %px\A\()_\B, SH_PX+\A+\B($66) @after %cs\B
        lqd     %py\A\()_\B, SH_PY+\A+\B($66) @after %cs\B
        lqd     %pz\A\()_\B, SH_PZ+\A+\B($66) @after %cs\B
        lqd     %vis\A\()_\B, \A+\B($83) @after %cs\B
        fm      %nn1\A\()_\B, %nx\A\()_\B, %nx\A\()_\B
        fma     %nn2\A\()_\B, %ny\A\()_\B, %ny\A\()_\B, %nn1\A\()_\B
        fma     %nn\A\()_\B, %nz\A\()_\B, %nz\A\()_\B, %nn2\A\()_\B
        fs      %lx\A\()_\B, $70, %px\A\()_\B
        fs      %ly\A\()_\B, $71, %py\A\()_\B
        fs      %lz\A\()_\B, $72, %pz\A\()_\B
        fm      %c1\A\()_\B, %nx\A\()_\B, %lx\A\()_\B
        fma     %c2\A\()_\B, %ny\A\()_\B, %ly\A\()_\B, %c1\A\()_\B
        fma     %c\A\()_\B, %nz\A\()_\B, %lz\A\()_\B, %c2\A\()_\B
        fm      %l1\A\()_\B, %lx\A\()_\B, %lx\A\()_\B
        fma     %l2\A\()_\B, %ly\A\()_\B, %ly\A\()_\B, %l1\A\()_\B
        fma     %ll\A\()_\B, %lz\A\()_\B, %lz\A\()_\B, %l2\A\()_\B
        fcgt    %lt1\A\()_\B, %c\A\()_\B, ZERO
        and     %lit\A\()_\B, %lt1\A\()_\B, %vis\A\()_\B
        fm      %x\A\()_\B, %nn\A\()_\B, %ll\A\()_\B
        frsqest %y0\A\()_\B, %x\A\()_\B
        fi      %y\A\()_\B, %x\A\()_\B, %y0\A\()_\B
        fm      %cs1\A\()_\B, %c\A\()_\B, %y\A\()_\B
        fcgt    %big\A\()_\B, %cs1\A\()_\B, $125
        selb    %cs2\A\()_\B, %cs1\A\()_\B, $125, %big\A\()_\B
        and     %cs\B, %cs2\A\()_\B, %lit\A\()_\B
        lqd     %ir\A\()_\B, \A+\B($85) @after %cs\B
        fma     %or\A\()_\B, %cs\B, $73, %ir\A\()_\B
      ~ stqd    %or\A\()_\B, SH_IRR_R+\A+\B($66)
        .if     \grey                        # r = g = b: one channel
      ~ stqd    %or\A\()_\B, SH_IRR_G+\A+\B($66)
      ~ stqd    %or\A\()_\B, SH_IRR_B+\A+\B($66)
        .else
        lqd     %ig\A\()_\B, 256+\A+\B($85) @after %cs\B
        lqd     %ib\A\()_\B, 512+\A+\B($85) @after %cs\B
        fma     %og\A\()_\B, %cs\B, $74, %ig\A\()_\B
        fma     %ob\A\()_\B, %cs\B, $75, %ib\A\()_\B
      ~ stqd    %og\A\()_\B, SH_IRR_G+\A+\B($66)
      ~ stqd    %ob\A\()_\B, SH_IRR_B+\A+\B($66)
        .endif
        lqd     %m\A\()_\B, SH_MAT+\A+\B($66) @after %cs\B
        ceq     %sel\A\()_\B, %m\A\()_\B, $87
        selb    %pat\A\()_\B, %pkeep, %ptake, %sel\A\()_\B
        fa      %ra\A\()_\B, %or\A\()_\B, $124
        fm      %rk\A\()_\B, %ra\A\()_\B, $121
        .if     \grey
        fm      %gk\A\()_\B, %ra\A\()_\B, $122
        fm      %bk\A\()_\B, %ra\A\()_\B, $123
        .else
        fa      %ga\A\()_\B, %og\A\()_\B, $124
        fa      %ba\A\()_\B, %ob\A\()_\B, $124
        fm      %gk\A\()_\B, %ga\A\()_\B, $122
        fm      %bk\A\()_\B, %ba\A\()_\B, $123
        .endif
        SH_COLOUR_OUT \A\()_\B, \A+\B, %cs\B
        .endr
        .endr
        .if     \grey
        hbrr    \label\()_br, .Lsh_shade_end
\label\()_br:
        br      .Lsh_shade_end
        .endif
        .endsched
        .endm
        .sched  pool=67,69,76-82,84,90-105,107-114,116-120,127 scratch=66-127
        ceq     %rg, $73, $74
        ceq     %rb, $73, $75
        ila     %zero, sh_zero
        ceq     %first, $85, %zero
        and     %grey1, %rg, %rb
        and     %grey, %grey1, %first
        brz     %grey, .Lsh_shade_gx          # a coloured light or sums: three channels
        .endsched
        SH_LIGHT_RUN .Lsh_shade_gw, 1
        SH_LIGHT_RUN .Lsh_shade_gx, 0
        .else
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
        .endif
.Lsh_shade_end:
        lqd     $84, SH_RUN+16($66)
        ceqi    $77, $86, -1                  # no material left: done
        lqd     $82, SH_RUN($66)
        gb      $77, $77
        lqd     $110, SH_RUN+32($66)
        ceqi    $77, $77, 15
        SH_ADDI $85, $66, SH_IRR_R            # the sums are stored now
        brz     $84, 2f                       # a later pass (or no light) is one run
        ai      $82, $82, SH_LIGHT_BYTES
        ai      $83, $83, 256
        ai      $84, $84, -1
        brnz    $84, .Lsh_run                 # the next light
2:      brz     $77, .Lsh_pass                # a material left: its pass

        # ---- 4. put the block to ea_colour + packet * 256
.Lsh_done:
        .ifdef  REFLECT                       # the block kept for the blend
        lqa     $70, rf_hold                  # (modules/reflect.s)
        brnz    $70, reflect_block
        .endif
        lqd     $70, SH_RUN_OUT($66)          # the block's EA, tag
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

