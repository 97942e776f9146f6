# shade_iset_slow.s — the i-set's slow path (modules/shade_iset.s describes the job): a
# step of the fast path that has an empty or mixed group, or a cache miss, is done again
# here group by group: mixed groups found in the caches by pairs of lanes, anything else
# lane by lane with the records and vertices fetched past the caches (sh_tri_miss,
# sh_vertex_miss in modules/shade_cache.s: $106 and $114 hold their addresses, $88 the
# return) and landed once per group. Out of line, after the end of shade_packet; back to
# the fast path's loop (.Lsh_group) or, after the last group, to .Lsh_iset_done. Saves
# and restores the fast path's $120..$124 (SH_SAVE) and reloads $92, $93, $120.
# With EXT_GATHER (the gather load) modules/shade_gather.s takes its place.

        .ifdef  EXT_GATHER
        .include "modules/shade_gather.s"   # the gather variant's: batched per packet
        .else
        # ---- out of line: the slow path, no light, a material miss

        # the slow path: an empty or mixed group, or a cache miss
.Lsh_slow:
        ai      $67, $67, -32
.Lsh_slow_group:                              # a group the fast path did not do
        lqd     $77, SH_DONE($66)
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

        .endif

.Lsh_empty:                                   # no ray hit
        il      $70, -1
        SH_ADDI $71, $66, SH_MAT
        .irp    Q, 0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 208, 224, 240
        stqd    $70, \Q($71)
        .endr
        br      .Lsh_iset_done

