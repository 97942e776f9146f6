# shade_iset_slow.s — the i-set's slow path (modules/shade_iset.s describes the job): a
# step of the fast path that has an empty or mixed group, or a cache miss, is done again
# here group by group: mixed groups found in the caches by pairs of lanes, anything else
# lane by lane with the records and vertices fetched past the caches (sh_tri_miss,
# sh_vertex_miss in modules/shade_cache.s: $106 and $114 hold their addresses, $88 the
# return) and landed once per group. Out of line, after the end of shade_packet; back to
# the fast path's loop (.Lsh_group) or, after the last group, to .Lsh_iset_done. Saves
# and restores the fast path's $120..$124 (SH_SAVE) and reloads $92, $93, $120.

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

        .ifdef  EXT_GATHER
        # The gather variant (--ext gather, docs/extensions.md): a group on different
        # triangles, whatever its misses, looked up for its 4 lanes at once with lgw
        # (the triangle tags, the records' columns, the vertex tags and normals) instead
        # of the mixed block below (all in the caches) or lane by lane (a miss). A
        # same-triangle group still goes lane by lane (its one record, its one lookup).
        # Only the missing lanes and vertices call the miss handlers, in lookup order;
        # a hit's normal is gathered before any lands (a miss may land in its line).
        .spu_ext gather
        .sched  pool=68,71-77,80-90,92-96,98,100-105,110-114,116-118,120,125-127 scratch=66-127
        a       %rp, $99, $67
        lqd     %ids, CTX_RAY_ID(%rp)
        ceqi    $69, %ids, -1                 # the lanes without a hit
        shufb   %s0, %ids, %ids, $91
        ceq     %same, %ids, %s0
        gb      %sameb, %same
        ceqi    %samec, %sameb, 15
        rotqbyi %r4, %ids, 4                  # a lane without a hit looks up the
        cgt     %c4, %ids, %r4                # largest id of the group (a hit's)
        selb    %m4, %r4, %ids, %c4
        rotqbyi %r8, %m4, 8
        cgt     %c8, %m4, %r8
        selb    %mx, %r8, %m4, %c8
        shufb   %mxs, %mx, %mx, $91
        selb    $70, %ids, %mxs, $69          # the ids looked up
        shufb   %tt, TTAGS, TTAGS, $91
        shufb   %td, TDATA, TDATA, $91
        shufb   %tm, TMASK, TMASK, $91
        and     %ti, $70, %tm
        shli    %to, %ti, 4
        lgwx    %tag, %tt, %to                # the lanes' triangle tags
        shli    %tl, %ti, 6
        a       %line, %tl, %td
        ceq     %th, %tag, $70
        or      %have, %th, $69
        xori    $78, %have, -1                # the lanes whose record is fetched
        shufb   %area, $66, $66, $91
        lqa     %lanes, sh_gather_lanes
        ila     %so, SH_STAGE
        a       %st0, %area, %so
        a       %st, %st0, %lanes
        selb    $79, %st, %line, %have        # each lane's record
        ila     $106, sh_tri_miss
        brnz    %samec, .Lsh_slow_body        # one triangle: lane by lane
        .endsched
        .irp    L, 0, 1, 2, 3                 # the records past the triangle cache
        rotqbyi $81, $78, 4*\L
        rotqbyi $80, $70, 4*\L
        SH_ADDI $82, $66, SH_STAGE+\L*64
        ila     $88, 1f
        binz    $81, $106
1:
        .endr
        SH_WAIT $85
        .sched  pool=68,71-77,80-90,92,94,96,100,106,114,120,125-127 scratch=66-127
        shufb   %vt, $115, $115, $91
        shufb   %vl, $123, $123, $91
        .irp    I, 0, 1, 2
        ai      %ra\I, $79, 48+4*\I
        lgw     %vi\I, %ra\I                  # vertex I's index, the lanes'
        and     %vx\I, %vi\I, $121
        shli    %vo\I, %vx\I, 4
        a       %va\I, %vo\I, %vt
        lgw     %tg\I, %va\I                  # its tag
        ceq     %h\I, %tg\I, %vi\I
        or      %hh\I, %h\I, $69
        shli    %lo\I, %vx\I, 6
        a       %ln\I, %lo\I, %vl
        .endr
        lgw     $104, %ln0                    # the normals the hits read, now
        ai      %ly0, %ln0, 4
        lgw     $105, %ly0
        ai      %lz0, %ln0, 8
        lgw     $110, %lz0
        lgw     $111, %ln1
        ai      %ly1, %ln1, 4
        lgw     $112, %ly1
        ai      %lz1, %ln1, 8
        lgw     $113, %lz1
        lgw     $116, %ln2
        ai      %ly2, %ln2, 4
        lgw     $117, %ly2
        ai      %lz2, %ln2, 8
        lgw     $118, %lz2
        ori     $93, %vi0, 0
        ori     $95, %vi1, 0
        ori     $98, %vi2, 0
        xori    $101, %hh0, -1                # the vertices that miss
        xori    $102, %hh1, -1
        xori    $103, %hh2, -1
        and     %a01, %hh0, %hh1
        and     %a012, %a01, %hh2
        gb      %ab, %a012
        ceqi    %allhit, %ab, 15
        hbrr    .Lsh_gather_br, .Lsh_gather_cols
.Lsh_gather_br:
        brnz    %allhit, .Lsh_gather_cols
        .endsched
        # a vertex missed: the misses one by one in lookup order (lane by lane, vertex by
        # vertex, as SH_NORMALS makes them), each call's return the next miss or the
        # landing (no branch back: the call's target and its return are both hinted),
        # landed, and their normals gathered from the lanes' SH_NRM slots where they
        # landed
        ila     $114, sh_vertex_miss
        lqd     $100, SH_BLOCK($66)           # the vertex records' EA
        .sched  pool=71-77,85-87,90,92,125-127 scratch=66-127
        andi    %b0, $101, 4                  # per lane, its vertices' misses: 0 in
        andi    %b1, $102, 2                  # bit 2, 1 in bit 1, 2 in bit 0
        andi    %b2, $103, 1
        or      %b01, %b0, %b1
        or      %b, %b01, %b2
        lqa     %sh, sh_gather_lanes+16
        shl     %bs, %b, %sh                  # lane 0's in bits 11..9, lane 3's in 2..0
        rotqbyi %r4, %bs, 4
        or      %o4, %bs, %r4
        rotqbyi %r8, %o4, 8
        or      $120, %o4, %r8
        .endsched
        .sched  pool=71-77,85-87,90 scratch=66-127
.Lsh_gmiss:
        hbr     .Lsh_gmiss_call, $114
        clz     %z, $120
        ai      %q, %z, -20                   # 3 lane + vertex, the highest bit's
        mpyi    %q11, %q, 11
        rotmi   %l, %q11, -5                  # the lane (q / 3 for q < 12)
        mpyi    %l3, %l, 3
        sf      %i, %l3, %q                   # the vertex
        ceqi    %i0, %i, 0
        ceqi    %i1, %i, 1
        selb    %v12, $98, $95, %i1
        selb    %vs, %v12, $93, %i0           # the vertex's lanes
        shli    %lb, %l, 2
        rotqby  $81, %vs, %lb                 # the vertex
        and     %x, $81, $121
        shli    %xo, %x, 4
        a       $83, %xo, $115                # its tag
        shli    %xl, %x, 6
        a       %ln, %xl, $123
        ai      $84, %ln, -16                 # its line
        shli    %lo, %l, 6
        shli    %io, %i, 4
        a       %o1, %lo, %io
        ila     %nb, SH_NRM
        a       $89, %o1, %nb                 # the lane's normal
        il      %top, 0x800
        sfi     %nq, %q, 0
        rotm    %bit, %top, %nq
        andc    $120, $120, %bit
        ila     %next, .Lsh_gmiss
        ila     %done, .Lsh_gmiss_done
        ceqi    %last, $120, 0
        selb    $88, %next, %done, %last      # back: the next miss, or the landing
.Lsh_gmiss_call:
        bi      $114
        .endsched
.Lsh_gmiss_done:
        SH_LAND
        .sched  pool=68,71-77,80-90,92,94,96,100,106,114,120,125-127 scratch=66-127
        shufb   %area, $66, $66, $91
        lqa     %lanes, sh_gather_lanes
        ila     %no, SH_NRM
        a       %b0, %area, %no
        a       %base, %b0, %lanes
        .irp    I, 0, 1, 2
        ai      %nx\I, %base, 16*\I
        ai      %ny\I, %base, 16*\I+4
        ai      %nz\I, %base, 16*\I+8
        lgw     %mx\I, %nx\I
        lgw     %my\I, %ny\I
        lgw     %mz\I, %nz\I
        .endr
        selb    $104, $104, %mx0, $101
        selb    $105, $105, %my0, $101
        selb    $110, $110, %mz0, $101
        selb    $111, $111, %mx1, $102
        selb    $112, $112, %my1, $102
        selb    $113, $113, %mz1, $102
        selb    $116, $116, %mx2, $103
        selb    $117, $117, %my2, $103
        selb    $118, $118, %mz2, $103
        .endsched
.Lsh_gather_cols:
        # the records' columns, the normal's differences, the group's values
        .sched  pool=68,70-78,80-90,92-96,98,100-103,106,114,120,125-127 scratch=66-127
        a       %gp, $66, $67
        .irp    W, 12, 16, 20, 24, 32, 36, 40, 60
        ai      %ra\W, $79, \W
        lgw     %w\W, %ra\W
        .endr
        or      %mat, %w60, $69               # no hit: no material
      ~ stqd    %mat, SH_MAT(%gp)
        fs      %d1x, $111, $104              # n1 - n0
        fs      %d1y, $112, $105
        fs      %d1z, $113, $110
        fs      %d2x, $116, $104              # n2 - n0
        fs      %d2y, $117, $105
        fs      %d2z, $118, $110
        a       %rp, $99, $67
        SH_GROUP_COLUMNS %w12, %w16, %w20, %w24, %w32, %w36, %w40, $104, $105, $110, %d1x, %d1y, %d1z, %d2x, %d2y, %d2z
        gb      %mb, $69
        cntb    %mc1, %mb                     # counted: a group, its hit lanes
        sfi     %hits, %mc1, 4
        lqd     %cg, SH_STATS+SHS_GROUPS($66)
        lqd     %ct, SH_STATS+SHS_TLOOK($66)
        ai      %cg1, %cg, 1
        a       %ct1, %ct, %hits
        stqd    %cg1, SH_STATS+SHS_GROUPS($66)
        stqd    %ct1, SH_STATS+SHS_TLOOK($66)
        hbrr    .Lsh_gather_next, .Lsh_slow_next
.Lsh_gather_next:
        br      .Lsh_slow_next
        .endsched
        .align  4
sh_gather_lanes:                              # the lanes' 64-byte strides
        .long   0, 64, 128, 192
        .long   9, 6, 3, 0                    # +16: the lanes' misses to bits
        .endif


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

.Lsh_empty:                                   # no ray hit
        il      $70, -1
        SH_ADDI $71, $66, SH_MAT
        .irp    Q, 0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 208, 224, 240
        stqd    $70, \Q($71)
        .endr
        br      .Lsh_iset_done

