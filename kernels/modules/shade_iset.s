# shade_iset.s — the shading module's job 1 (modules/shade.s): the i-set, and its fast path.
#
# Per intersection packet of 4 rays, a flag says whether all 4 hit the same triangle; then
# its record (64 bytes: the barycentric rows and, in the spare 16 bytes, the vertex and
# material indices) and its three vertex normals are fetched once and splatted to the 4
# lanes; otherwise per lane, the lanes' rows transposed into columns. Vertices go through
# a direct-mapped cache of 64-byte records (ShadingBlock.vertex_cache_log2 entries). Per
# ray the hit point o + t d, its barycentrics (the projection of the record, as the hit
# test computed them), the interpolated normal facing the eye and the material are stored
# structure-of-arrays (SH_NX.., SH_PX.., SH_MAT). Three paths, the hot ones scheduled
# `.sched` blocks: same-triangle packets found in the caches, two per step (here);
# mixed packets found in the caches, and anything else (a cache miss, no hit) lane by
# lane (modules/shade_iset_slow.s), its vertex misses fetched without waiting into staging
# slots and landed together once its lanes are looked up (sh_vertex_miss, SH_LAND: one
# wait per packet of 4 rays, not one per miss; the triangle records past the traversal's
# cache likewise, one wait before they are read). They compute the same values and
# counts. A packet none of whose rays hit has no i-set (its materials -1, the counters as
# they are).
#
# The macros below are the slow path's (the vertex cache's lookup and landing, the
# records' staging, the columns' arithmetic); the code is the fast path, entered from
# shade_packet's prologue at .Lsh_ready with $66 = the area, $99 = the rays, $97 = the
# packet number, $91..$93 and $119..$122 the splat and sign patterns, $107..$109 the
# origin's splats, $115 the vertex tags, $123 the vertex lines' normals, $117 = "no ray
# hit"; it leaves to .Lsh_iset_done (modules/shade_light.s) with the i-set built and
# $124 = the fast groups' counts, or to the slow path (.Lsh_slow) for a step it cannot do.

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
      ~ stqd    %okp, SH_DONE($66)          # which of the two groups are done
        .ifdef  EXT_GATHER                  # which are on one cached triangle and
        andc    %cnd0, %ok20, %h0120        # missed a vertex (modules/shade_gather.s:
        andc    %cnd16, %ok216, %h01216     # fetched at once)
        shufb   %cndp, %cnd0, %cnd16, $119
      ~ stqa    %cndp, sh_gcand
        .endif
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

