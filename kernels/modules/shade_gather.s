# shade_gather.s — the i-set's slow path for SPUs with the gather load (--ext gather,
# docs/extensions.md): the groups the fast path (modules/shade_iset.s) could not do are
# batched per packet instead of done one by one, so a packet waits for main memory at
# most twice (its missing triangle records, then its groups' vertex normals), not twice
# per group, and every lookup is a gather (lgw, lgwx) from local store.
#
# The fast path runs all 8 of its steps; a step it cannot finish (.Lsh_slow) whose group
# on one cached triangle only missed a vertex has that group's normals fetched at once
# and runs again (.Lsh_rescue), else it is noted in sh_gfail (which of its two groups
# the fast path did, and the step) and the loop goes on. Then (.Lsh_gbatch, also from
# .Lsh_iset_done when the last step was done):
#   A. per group not done: its lanes' triangle tags (lgwx); a group with a record past
#      the traversal's triangle cache gets its 4 records by one DMA list for the packet
#      (sh_glr, into sh_grec), the others read the cache's lines; a group with no hit
#      gets material -1.
#   B. per such group: the vertex indices and the vertex cache's tags (lgw); a group with
#      a vertex miss gets its 12 vertex normals (the quadword of each record the module
#      reads) by one DMA list for the packet (sh_glv, into sh_gnst), the others read the
#      cache's lines.
#   C. per such group: the normals' and the records' columns (lgw) and the group's
#      values, as SH_GROUP_COLUMNS computes them for every path.
#   D. per group that missed: each of its 12 lookups (all fetched; a hit's is the same
#      vertex and normal again) to its line and tag, in lookup order (so a line holds the
#      last vertex looked up there), for the fast path of later packets.
# The baseline's slow path is not assembled in this variant. Registers as the fast path's
# (modules/shade_iset.s); the loops' own state is in $80..$85 and $119, lgwx's offsets in
# $67, $92, $93, $120 (and $82, $84, $85 in C); .Lsh_gdone restores the fast path's
# patterns. Also here: the lighting's later passes (.Lsh_later_g, modules/shade_light.s).

        .spu_ext gather

        # a step of the fast path with a group it could not do. A group on one triangle
        # whose record is in the triangle cache failed for a vertex the vertex cache
        # lacks: its 3 normals are fetched and landed now (one wait) and the step run
        # again, once (sh_gresc: the step rerun), so the packet's later groups on its
        # triangle find them too instead of all falling into the batch. Any other
        # failure (or the rerun's) is noted for the batch and the loop goes on.
        .sched  pool=68-79,86-90,94-96,98,100-106,110-114,116-118,125-127 scratch=66-127
.Lsh_rescue:
        lqd     %okp, SH_DONE($66)            # its groups' flags (words 0, 2)
        ai      %st, $67, -32                 # the step's first group * 16
        a       %rp, $99, %st
        lqd     %blk, SH_BLOCK($66)           # the vertex records' EA
        shufb   %evs, %blk, %blk, $91
        ai      %ev, %evs, 16                 # (their normals)
        il      %sz, 16
        lqa     %plo, sh_const
        lqa     %phi, sh_const+16
        lqa     %w3, sh_gather_lanes+16       # words 0-2
        .irp    H, 0, 16
        rotqbyi %ok\H, %okp, \H/2
        lqd     %ids\H, CTX_RAY_ID+\H(%rp)
        shufb   %s0\H, %ids\H, %ids\H, $91
        ceq     %same\H, %ids\H, %s0\H
        gb      %sb\H, %same\H
        ceqi    %all\H, %sb\H, 15
        ceqi    %miss\H, %ids\H, -1
        andc    %c1\H, %all\H, %miss\H
        andc    %c2\H, %c1\H, %ok\H
        and     %ti\H, %ids\H, TMASK
        shli    %to\H, %ti\H, 4
        lqx     %tag\H, TTAGS, %to\H
        shli    %tl\H, %ti\H, 6
        a       %line\H, %tl\H, TDATA
        ceq     %th\H, %tag\H, %ids\H
        and     %c3\H, %c2\H, %th\H
        lqd     %q3\H, 48(%line\H)            # vertex indices, material
        and     %vi\H, %q3\H, %w3
        and     %x\H, %vi\H, $121
        shli    %vo0\H, %x\H, 4
        rotqbyi %vo1\H, %vo0\H, 4
        rotqbyi %vo2\H, %vo0\H, 8
        lqx     %vt0\H, $115, %vo0\H
        lqx     %vt1\H, $115, %vo1\H
        lqx     %vt2\H, $115, %vo2\H
        rotqbyi %v1\H, %vi\H, 4
        rotqbyi %v2\H, %vi\H, 8
        ceq     %h0\H, %vt0\H, %vi\H
        ceq     %h1\H, %vt1\H, %v1\H
        ceq     %h2\H, %vt2\H, %v2\H
        and     %h01\H, %h0\H, %h1\H
        and     %hall\H, %h01\H, %h2\H
        andc    %cand\H, %c3\H, %hall\H        # one triangle, cached, a vertex missed
        shufb   %cs\H, %cand\H, %cand\H, $91
        and     %vf\H, %vi\H, %cs\H             # the vertices fetched (else vertex 0)
        shli    %eo\H, %vf\H, 6
        a       %ea\H, %eo\H, %ev
        shufb   %e0\H, %sz, %ea\H, %plo         # list elements: 16 bytes, the EA
        shufb   %e1\H, %sz, %ea\H, %phi
        stqa    %e0\H, sh_grlist+2*\H
        stqa    %e1\H, sh_grlist+2*\H+16
        stqa    %vi\H, sh_grv+\H
        stqa    %cs\H, sh_grv+32+\H
        a       %hs\H, %h0\H, %h1\H              # its misses: 3 - hits
        a       %hs2\H, %hs\H, %h2\H
        ai      %mc\H, %hs2\H, 3
        and     %mcc\H, %mc\H, %cand\H
        .endr
        a       $80, %mcc0, %mcc16
        lqa     %cinc, sh_const+240           # the fast step's counts, to be undone
        shufb   %okv0, %ok0, %ok0, $91
        shufb   %okv16, %ok16, %ok16, $91
        and     %inc0, %cinc, %okv0
        and     %inc16, %cinc, %okv16
        a       $82, %inc0, %inc16
        .endsched
        ila     $83, sh_grst
        ila     $84, sh_grlist
        il      $85, 64
        il      $86, SH_TAG
        il      $87, 0x44                     # getl
        wrch    $MFC_LSA, $83
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $84
        wrch    $MFC_Size, $85
        wrch    $MFC_TagID, $86
        wrch    $MFC_Cmd, $87
        stqa    $81, sh_gresc
        lqd     $83, SH_STATS+SHS_VMISS($66)
        sf      $124, $82, $124
        a       $83, $83, $80
        stqd    $83, SH_STATS+SHS_VMISS($66)
        SH_WAIT $86
        # landed in lookup order (vertex 0, 1, 2; the step's first group first), a group
        # not fetched to a spare quadword
        .sched  pool=68-79,86-90,94-96,98,100-106,110-114,116-118,125-127 scratch=66-127
        ila     %dm, sh_grspare
        sf      %dl1, $123, %dm
        sf      %dt1, $115, %dm
        shufb   %dl, %dl1, %dl1, $91
        shufb   %dt, %dt1, %dt1, $91
        .irp    H, 0, 16
        lqa     %vi\H, sh_grv+\H
        lqa     %c\H, sh_grv+32+\H
        and     %x\H, %vi\H, $121
        shli    %xl\H, %x\H, 6
        shli    %xt\H, %x\H, 4
        selb    %ol\H, %dl, %xl\H, %c\H
        selb    %ot\H, %dt, %xt\H, %c\H
        .irp    I, 0, 1, 2
        rotqbyi %v\I\()\H, %vi\H, 4*\I
        rotqbyi %l\I\()\H, %ol\H, 4*\I
        rotqbyi %t\I\()\H, %ot\H, 4*\I
        lqa     %n\I\()\H, sh_grst+4*\H+16*\I
        stqx    %n\I\()\H, $123, %l\I\()\H           # the normal to its line
        stqx    %v\I\()\H, $115, %t\I\()\H           # the vertex to its tag
        .endr
        .endr
        ai      $67, $67, -32                 # the step again
        hbrr    .Lsh_rescue_br, .Lsh_group
.Lsh_rescue_br:
        br      .Lsh_group
        .endsched

.Lsh_slow:
        .sched  pool=68-79,86-90,94-96,98,100-106,110-114,116-118,125-127 scratch=66-127
      ! hbrr    .Lsh_slow_back, .Lsh_group
        lqa     %cp, sh_gcand                 # (the fast step's: words 0, 2)
        rotqbyi %cp2, %cp, 8
        or      %any, %cp, %cp2
        shli    %pk, $97, 9
        or      $81, %pk, $67                 # this step of this packet
        lqa     %last, sh_gresc
        ceq     %again, $81, %last            # its rerun: no second rescue
        andc    %go, %any, %again
        lqd     %okp, SH_DONE($66)            # noted (counted only if not fetched now):
        lqa     %n, sh_gn                     # its groups' flags (words 0, 2) and its
        ai      %fst, $67, -32                # first group * 16
        ila     %fb, sh_gfail
        ila     %sb, sh_gstep
        ceqi    $80, $67, 256
        stqx    %okp, %fb, %n
        stqx    %fst, %sb, %n
        il      %sixteen, 16
        andc    %inc, %sixteen, %go
        a       %n1, %n, %inc
        stqa    %n1, sh_gn
        stqa    ZERO, sh_gresc
        brnz    %go, .Lsh_rescue
        .endsched
.Lsh_slow_back:
        brz     $80, .Lsh_group
        # (after the last step: the batch)

        # ---- the batch: A. the groups' records
.Lsh_gbatch:
        lqa     $81, sh_gn                    # the steps noted * 16
        il      $80, 0
        il      $82, 0                        # groups to do * 256
        il      $83, 0                        # records' list bytes (32 a group)
        il      $84, 0                        # records fetched
.Lsh_gstep:                                   # (both groups of a step in one block: the
        .sched  pool=68-79,86-90,94-96,98,100-106,110-114,116-118,125-127 scratch=66-127
        ila     %gfb, sh_gfail
        ila     %gsb, sh_gstep
        lqx     %okp, %gfb, $80
        lqx     %st, %gsb, $80
        shufb   %tt, TTAGS, TTAGS, $91
        shufb   %td, TDATA, TDATA, $91
        shufb   %tm, TMASK, TMASK, $91
        shufb   %eat, EATRIS, EATRIS, $91
        lqa     %plo, sh_const
        lqa     %phi, sh_const+16
        lqa     %lanes, sh_gather_lanes
        il      %sz, 64
        ila     %lrb, sh_glr
        ila     %grb, sh_grec
        ila     %gkb, sh_gk
        .irp    H, 0, 1                       # second's stores after the first's)
        rotqbyi %ok\H, %okp, 8*\H               # the fast path did it
        ai      %g\H, %st, 16*\H                # the group * 16
        a       %rp\H, $99, %g\H
        a       %gp\H, $66, %g\H
        lqd     %ids\H, CTX_RAY_ID(%rp\H)
        ceqi    %nh\H, %ids\H, -1                 # the lanes without a hit
        gb      %nhb\H, %nh\H
        ceqi    %allm\H, %nhb\H, 15
        rotqbyi %r4\H, %ids\H, 4                  # a lane without a hit looks up the
        cgt     %c4\H, %ids\H, %r4\H                # largest id of the group (a hit's)
        selb    %m4\H, %r4\H, %ids\H, %c4\H
        rotqbyi %r8\H, %m4\H, 8
        cgt     %c8\H, %m4\H, %r8\H
        selb    %mx\H, %r8\H, %m4\H, %c8\H
        shufb   %mxs\H, %mx\H, %mx\H, $91
        selb    %idv\H, %ids\H, %mxs\H, %nh\H         # the ids looked up
        and     %ti\H, %idv\H, %tm
        shli    %to\H, %ti\H, 4
        lgwx    %tag\H, %tt, %to\H                # the lanes' triangle tags
        shli    %tl\H, %ti\H, 6
        a       %line\H, %tl\H, %td
        ceq     %th\H, %tag\H, %idv\H
        or      %have\H, %th\H, %nh\H
        gb      %hb\H, %have\H
        ceqi    %allh\H, %hb\H, 15                # every record in the cache
        shli    %eo\H, %idv\H, 6
        a       %ea\H, %eo\H, %eat
        shufb   %e0\H, %sz, %ea\H, %plo
        shufb   %e1\H, %sz, %ea\H, %phi
        a       %lra\H, %lrb, $83
        stqd    %e0\H, 0(%lra\H)
        stqd    %e1\H, 16(%lra\H)
        shli    %ro\H, $83, 3
        a       %rb0\H, %grb, %ro\H
        shufb   %rbs\H, %rb0\H, %rb0\H, $91
        a       %rec\H, %rbs\H, %lanes
        shufb   %ahs\H, %allh\H, %allh\H, $91
        selb    %ra\H, %rec\H, %line\H, %ahs\H        # each lane's record
        or      %skip\H, %ok\H, %allm\H
        nor     %fe\H, %allh\H, %skip\H             # its records fetched
        andi    %fe32\H, %fe\H, 32
        a       $83, $83, %fe32\H
        xori    %nhv\H, %hb\H, 15
        cntb    %nc\H, %nhv\H
        and     %nc2\H, %nc\H, %fe\H
        a       $84, $84, %nc2\H
        lqd     %om\H, SH_MAT(%gp\H)              # no hit: no material
        andc    %em\H, %allm\H, %ok\H
        shufb   %ems\H, %em\H, %em\H, $91
        selb    %nm\H, %om\H, %nh\H, %ems\H
      ~ stqd    %nm\H, SH_MAT(%gp\H)
        a       %gka\H, %gkb, $82
        stqd    %g\H, 0(%gka\H)
        stqd    %ra\H, 16(%gka\H)
        stqd    %nh\H, 32(%gka\H)
        nor     %d\H, %skip\H, %skip\H              # to do
        andi    %d256\H, %d\H, 256
        a       $82, $82, %d256\H
        .endr
        ai      $80, $80, 16
        ceq     %end, $80, $81
        hbrr    .Lsh_gstep_br, .Lsh_gstep
.Lsh_gstep_br:
        brz     %end, .Lsh_gstep
        .endsched
        il      $86, 0
        stqa    $86, sh_gn                    # (the next packet's steps)
        lqd     $86, SH_STATS+SHS_TMISS($66)
        a       $86, $86, $84
        stqd    $86, SH_STATS+SHS_TMISS($66)
        brz     $83, .Lsh_gv                  # no record to fetch
        ila     $86, sh_grec
        ila     $87, sh_glr
        il      $88, SH_TAG
        il      $89, 0x44                     # getl
        wrch    $MFC_LSA, $86
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $87
        wrch    $MFC_Size, $83
        wrch    $MFC_TagID, $88
        wrch    $MFC_Cmd, $89
        SH_WAIT $86

        # ---- B. the groups' vertices
.Lsh_gv:
        il      $80, 0
        il      $84, 0                        # vertices missed
        il      $85, 0                        # normals' list bytes (96 a group)
        il      $81, 0                        # groups with a miss * 16 (sh_gml)
        il      $83, 0                        # groups without * 16 (sh_gmh)
        il      $67, 4                        # lgwx's offsets (B and C; C's others at
        il      $92, 8                        # .Lsh_gc)
        brz     $82, .Lsh_gdone               # no group to do
        lqa     $119, sh_gk+16                # the group's records (the next one's
.Lsh_gvloop:                                  # loaded by the iteration before)
        .sched  pool=68-79,86-90,94-96,98,100-106,110-114,116-118,125-127 scratch=66-127
        ila     %gkb, sh_gk
        a       %gka, %gkb, $80
        ai      %ra48, $119, 48
        lqd     $119, 256+16(%gka)
        lqd     %nh, 32(%gka)
        lqd     %blk, SH_BLOCK($66)           # the vertex records' EA
        shufb   %evs, %blk, %blk, $91
        ai      %ev, %evs, 16                 # (their normals)
        shufb   %vt, $115, $115, $91
        shufb   %vl, $123, $123, $91
        il      %sz, 16
        lqa     %plo, sh_const
        lqa     %phi, sh_const+16
        ila     %lvb, sh_glv
        a       %lva, %lvb, $85
        lgw     %vi0, %ra48                   # vertex I's index, the lanes'
        lgwx    %vi1, %ra48, $67
        lgwx    %vi2, %ra48, $92
        .irp    I, 0, 1, 2
        and     %x\I, %vi\I, $121
        shli    %to\I, %x\I, 4
        lgwx    %tg\I, %vt, %to\I              # its tag
        ceq     %h\I, %tg\I, %vi\I
        or      %hh\I, %h\I, %nh
        xori    %m\I, %hh\I, -1               # missed
        shli    %lo\I, %x\I, 6
        a       %ln\I, %lo\I, %vl             # its line's normal
        shli    %eo\I, %vi\I, 6
        a       %ea\I, %eo\I, %ev
        shufb   %el\I, %sz, %ea\I, %plo       # list elements: 16 bytes, the EA
        shufb   %eh\I, %sz, %ea\I, %phi
      ~ stqd    %el\I, 32*\I(%lva)
      ~ stqd    %eh\I, 32*\I+16(%lva)
      ~ stqd    %vi\I, 96+16*\I(%gka)
      ~ stqd    %m\I, 144+16*\I(%gka)
        gb      %mb\I, %m\I
        .endr
        and     %a01, %hh0, %hh1
        and     %a, %a01, %hh2
        gb      %ab, %a
        ceqi    %allhit, %ab, 15
        shufb   %ahs, %allhit, %allhit, $91
        shli    %n2, $85, 1                   # the group's normals' slots: 64 bytes a
        ila     %nsb, sh_gnst                 # vertex, 16 a lane
        a       %ns0, %nsb, %n2
        shufb   %nss, %ns0, %ns0, $91
        lqa     %l16, sh_gather_lanes+32
        a       %ns, %nss, %l16
        .irp    I, 0, 1, 2
        ai      %nsi\I, %ns, 64*\I
        selb    %na\I, %nsi\I, %ln\I, %ahs
      ~ stqd    %na\I, 48+16*\I(%gka)
        .endr
        shli    %mb0s, %mb0, 8                # the misses, lookup order (vertex, lane)
        shli    %mb1s, %mb1, 4                # from bit 11 down
        or      %mb01, %mb0s, %mb1s
        or      %mbits, %mb01, %mb2
      ~ stqd    %mbits, 192(%gka)
        cntb    %mc, %mbits
        rotqbyi %mc2, %mc, 2
        a       %mc3, %mc, %mc2
        andi    %mc4, %mc3, 255
        a       $84, $84, %mc4
        xori    %nah, %allhit, -1
        andi    %n96, %nah, 96
        a       $85, $85, %n96
        ila     %mlb, sh_gml
        ila     %hlb, sh_gmh
        stqx    $80, %mlb, $81                # the group, listed as missing or not
        stqx    $80, %hlb, $83
        andi    %n16, %nah, 16
        andi    %h16, %allhit, 16
        a       $81, $81, %n16
        a       $83, $83, %h16
        ai      $80, $80, 256
        ceq     %end, $80, $82
        hbrr    .Lsh_gv_br, .Lsh_gvloop
.Lsh_gv_br:
        brz     %end, .Lsh_gvloop
        .endsched
        lqd     $86, SH_STATS+SHS_VMISS($66)
        a       $86, $86, $84
        stqd    $86, SH_STATS+SHS_VMISS($66)
        brz     $85, .Lsh_gc                  # every vertex in the cache
        ila     $86, sh_gnst
        ila     $87, sh_glv
        il      $88, SH_TAG
        il      $89, 0x44                     # getl (waited for after the groups that
        wrch    $MFC_LSA, $86                 # hit are done)
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $87
        wrch    $MFC_Size, $85
        wrch    $MFC_TagID, $88
        wrch    $MFC_Cmd, $89

        # ---- C. the groups' values: first those that hit, then (their normals waited
        # for) those that missed
# the groups listed at LIST (END: its bytes), looped at LOOP (BR its branch)
# ($119: the group's record in sh_gk, the next one's found by the iteration before)
        .macro  SH_GATHER_GROUPS list, end, loop, br
        lqa     $87, \list
        ila     $86, sh_gk
        a       $119, $86, $87
\loop:
        .sched  pool=68-79,86-90,94-96,98,100-106,110-114,116-118,125-127 scratch=66-127
        ila     %gkb, sh_gk
        ila     %lsb, \list
        lqd     %g, 0($119)
        lqd     %ra, 16($119)
        lqd     %nh, 32($119)
        lqd     %na0, 48($119)
        lqd     %na1, 64($119)
        lqd     %na2, 80($119)
        a       %gp, $66, %g
        a       %rp, $99, %g
        .irp    I, 0, 1, 2
        lgw     %nx\I, %na\I
        lgwx    %ny\I, %na\I, $67            # (+4)
        lgwx    %nz\I, %na\I, $92            # (+8)
        .endr
        lgwx    %w12, %ra, $93                # the records' words 3, 4-6, 8-10, 15
        lgwx    %w16, %ra, $120
        lgwx    %w20, %ra, $82
        lgwx    %w24, %ra, $84
        ai      %ra32, %ra, 32
        lgw     %w32, %ra32
        lgwx    %w36, %ra32, $67
        lgwx    %w40, %ra32, $92
        lgwx    %w60, %ra, $85
        or      %mat, %w60, %nh               # no hit: no material
      ~ stqd    %mat, SH_MAT(%gp)
        fs      %d1x, %nx1, %nx0              # n1 - n0
        fs      %d1y, %ny1, %ny0
        fs      %d1z, %nz1, %nz0
        fs      %d2x, %nx2, %nx0              # n2 - n0
        fs      %d2y, %ny2, %ny0
        fs      %d2z, %nz2, %nz0
        SH_GROUP_COLUMNS %w12, %w16, %w20, %w24, %w32, %w36, %w40, %nx0, %ny0, %nz0, %d1x, %d1y, %d1z, %d2x, %d2y, %d2z
        lqd     %ids, CTX_RAY_ID(%rp)         # counted: a group, its records looked
        shufb   %s0, %ids, %ids, $91          # up (one for one triangle), one triangle
        ceq     %same, %ids, %s0
        gb      %sameb, %same
        ceqi    %samec, %sameb, 15
        gb      %mb, %nh
        cntb    %mc1, %mb
        sfi     %hits, %mc1, 4
        il      %one, 1
        selb    %looks, %hits, %one, %samec
        lqd     %cg, SH_STATS+SHS_GROUPS($66)
        lqd     %ct, SH_STATS+SHS_TLOOK($66)
        lqd     %cs, SH_STATS+SHS_SAME($66)
        ai      %cg1, %cg, 1
        a       %ct1, %ct, %looks
        sf      %cs1, %samec, %cs
        stqd    %cg1, SH_STATS+SHS_GROUPS($66)
        stqd    %ct1, SH_STATS+SHS_TLOOK($66)
        stqd    %cs1, SH_STATS+SHS_SAME($66)
        ai      $80, $80, 16
        lqx     %k, %lsb, $80                 # the next group
        a       $119, %gkb, %k
        ceq     %end, $80, \end
        hbrr    \br, \loop
\br:
        brz     %end, \loop
        .endsched
        .endm

.Lsh_gc:
        il      $80, 0
        il      $93, 12                       # lgwx's offsets ($67: 4, $92: 8)
        il      $120, 16
        il      $82, 20
        il      $84, 24
        il      $85, 60
        brz     $83, .Lsh_gcm0
        SH_GATHER_GROUPS sh_gmh, $83, .Lsh_gch, .Lsh_gch_br
.Lsh_gcm0:
        brz     $81, .Lsh_gdone               # no vertex missed
        SH_WAIT $86
        il      $80, 0
        SH_GATHER_GROUPS sh_gml, $81, .Lsh_gcm, .Lsh_gcm_br

        # ---- D. the vertex cache: a group with a miss has all 12 of its normals fetched,
        # so each of its lookups (a hit's too: the same vertex and normal again) is
        # stored to its line and tag, in lookup order (vertex, lane), without a branch
        il      $80, 0
        lqa     $87, sh_gml
        ila     $86, sh_gk
        a       $83, $86, $87                 # the group's record (the next one's
.Lsh_gland:                                   # found by the iteration before)
        .sched  pool=68-79,86-90,94-96,98,100-106,110-114,116-118,125-127 scratch=66-127
        lqd     %nb, 48($83)                  # its normals' slots (lane 0's, vertex 0)
        .irp    I, 0, 1, 2
        lqd     %vi\I, 96+16*\I($83)
        and     %x\I, %vi\I, $121
        shli    %xl\I, %x\I, 6
        rotmi   %t\I\()0, %xl\I, -2             # lane 0 (in the preferred slot)
        lqd     %n\I\()0, 64*\I(%nb)
        stqx    %n\I\()0, $123, %xl\I
        stqx    %vi\I, $115, %t\I\()0
        .irp    L, 1, 2, 3
        rotqbyi %v\I\L, %vi\I, 4*\L
        rotqbyi %o\I\L, %xl\I, 4*\L
        rotmi   %t\I\L, %o\I\L, -2
        lqd     %n\I\L, 64*\I+16*\L(%nb)
        stqx    %n\I\L, $123, %o\I\L           # the normal to its line
        stqx    %v\I\L, $115, %t\I\L           # the vertex to its tag
        .endr
        .endr
        ai      $80, $80, 16
        ila     %lsb, sh_gml
        lqx     %k, %lsb, $80
        ila     %gkb, sh_gk
        a       $83, %gkb, %k
        ceq     %end, $80, $81
        hbrr    .Lsh_gland_br, .Lsh_gland
.Lsh_gland_br:
        brz     %end, .Lsh_gland
        .endsched
.Lsh_gdone:
        lqa     $92, sh_const+80              # (the fast path's patterns)
        lqa     $119, sh_const+32
        lqa     $93, sh_const+96
        lqa     $120, sh_const+208
        br      .Lsh_iset_done

        # A later pass of the lighting (modules/shade_light.s, .Lsh_run with no light
        # left: a black light) shades from the stored sums without computing the
        # irradiance it would add 0 to: the same colours and stores as .Lsh_shade_g's
        # (or, og, ob are the sums: cs * 0 + s = s, the SPU having no NaN), in 15 even-
        # pipe instructions a group instead of 43. It needs no gather. All 16 groups in
        # one block, as .Lsh_shade_gx: a group's loads wait for the group two before it
        # (%ra\B), and its two selects are one pattern and two shufb.
        .sched  pool=67,69,76-82,84,90-105,107-114,116-120,127 scratch=66-127
.Lsh_later_g:
        hbrr    .Lsh_later_br, .Lsh_shade_end
        il      %none, -1
        lqa     %pkeep, sh_gsel               # bytes of a, of b (shufb)
        lqa     %ptake, sh_gsel+16
        .irp    A, 0, 32, 64, 96, 128, 160, 192, 224
        .irp    B, 0, 16
        lqd     %or\A\()_\B, \A+\B($85) @after %ra\B      # the sums
        lqd     %og\A\()_\B, 256+\A+\B($85) @after %ra\B
        lqd     %ob\A\()_\B, 512+\A+\B($85) @after %ra\B
      ~ stqd    %or\A\()_\B, SH_IRR_R+\A+\B($66)
      ~ stqd    %og\A\()_\B, SH_IRR_G+\A+\B($66)
      ~ stqd    %ob\A\()_\B, SH_IRR_B+\A+\B($66)
        lqd     %m\A\()_\B, SH_MAT+\A+\B($66) @after %ra\B
        ceq     %sel\A\()_\B, %m\A\()_\B, $87            # this shader's rays
        selb    %pat\A\()_\B, %pkeep, %ptake, %sel\A\()_\B
        fa      %ra\B, %or\A\()_\B, $124
        fa      %ga\A\()_\B, %og\A\()_\B, $124
        fa      %ba\A\()_\B, %ob\A\()_\B, $124
        fm      %rk\A\()_\B, %ra\B, $121
        fm      %gk\A\()_\B, %ga\A\()_\B, $122
        fm      %bk\A\()_\B, %ba\A\()_\B, $123
        SH_COLOUR_OUT \A\()_\B, \A+\B, %ra\B
        .endr
        .endr
.Lsh_later_br:
        br      .Lsh_shade_end
        .endsched

        .align  4
sh_gather_lanes:                              # the lanes' 64-byte strides
        .long   0, 64, 128, 192
        .long   -1, -1, -1, 0                 # +16: words 0-2
        .long   0, 16, 32, 48                 # +32: the lanes' 16-byte strides
sh_gsel:                                      # shufb: a's bytes; b's (.Lsh_shade_gx)
        .long   0x00010203, 0x04050607, 0x08090a0b, 0x0c0d0e0f
        .long   0x10111213, 0x14151617, 0x18191a1b, 0x1c1d1e1f
sh_gn:  .long   0, 0, 0, 0                    # the steps noted * 16
sh_gcand:                                     # the fast step's groups to fetch at once
        .long   0, 0, 0, 0
sh_gresc:                                     # the step rerun (packet << 9 | step + 32)
        .long   0, 0, 0, 0
sh_grv:                                       # the rescue: vertices (2 groups), fetched?
        .space  64
sh_grspare:                                   # (a group not fetched lands here)
        .space  16
sh_grlist:                                    # its list (4 elements a group)
        .space  64
sh_grst:                                      # its normals (4 a group)
        .space  128
sh_gfail:                                     # per step noted: its groups' flags
        .space  128
sh_gstep:                                     # ... and its first group * 16
        .space  128
        .align  7
sh_gk:                                        # per group to do: the group * 16, the
        .space  16 * 256                      # lanes' records, no-hit lanes, normals'
                                              # addresses (3), vertices (3), misses (3),
                                              # the misses' bits (+192)
sh_grec:                                      # the records fetched (4 a group)
        .space  16 * 256
sh_gnst:                                      # the normals fetched (12 a group)
        .space  16 * 192
sh_glr:                                       # the records' list (4 elements a group)
        .space  16 * 32
sh_glv:                                       # the normals' list (12 elements a group)
        .space  16 * 96
sh_gml:                                       # the groups with a vertex miss (their
        .space  16 * 16                       # offsets in sh_gk)
sh_gmh:                                       # ... and those without
        .space  16 * 16
