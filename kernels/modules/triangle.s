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
        lqa     $80, vars+V_LEAVES
        ai      $80, $80, 1
        stqa    $80, vars+V_LEAVES
        # a new visit: what the staging slots hold is from an older leaf
        il      $86, -1
        .irp    J, 0, 1, 2, 3, 4, 5, 6, 7
        stqd    $86, CTX_STAGE_TAGS+\J*16(RAYS)
        .endr
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
        brz     $78, tri_loop
        lqa     $86, vars+V_NCTX1
        brz     $86, .Lpf_suspend
        lqd     $86, CTX_TAG(RAYS)
        rotqbyi $87, $86, 4
        il      $86, 2
        wrch    $MFC_WrTagMask, $87
        wrch    $MFC_WrTagUpdate, $86
        rdch    $86, $MFC_RdTagStat
tri_loop:
        ai      S_TLOOK, S_TLOOK, 1
        and     $80, $66, TMASK
        shli    $81, $80, 4
        shli    $82, $80, 6
        lqx     $83, TTAGS, $81
        a       $84, TDATA, $82
        ceq     $85, $83, $66
        brz     $85, tri_miss                 # hits fall through
        # (scheduled into even/odd pairs: the record's splats, the corner-ray frustum cull
        # of the triangle, the first active group's offset)
        .align  3
.Ltri_hit:
        ila     $90, k_axoff
        lqd     $86, TRI_N_U($84)   # (n_u, n_v, n_d, k)
        ori     $97, RAYS, 0
        lqd     $87, TRI_B_NU($84)   # (b_nu, b_nv, b_d, -)
        rotmi   $119, FIRST, -4
        lqd     $88, TRI_C_NU($84)   # (c_nu, c_nv, c_d, -)
        nop
        shufb   $124, $66, $66, PAT0   # triangle index
        shli    $119, $119, 6   # byte offset of the first group
        rotqbyi $89, $86, 12   # k
        nop
        shufb   $68, $86, $86, PAT0   # n_u
        nop
        shufb   $69, $86, $86, PAT1   # n_v
        nop
        shufb   $93, $86, $86, PAT2   # n_d
        shli    $89, $89, 4
        shufb   $71, $87, $87, PAT0   # b_nu
        fm      $95, $68, $68
        shufb   $73, $87, $87, PAT2   # b_d
        nop
        shufb   $74, $88, $88, PAT0   # c_nu
        nop
        shufb   $120, $88, $88, PAT2   # c_d
        nop
        lqx     $91, $90, $89   # (k, u, v) array offsets
        ila     $90, k_kuv
        shufb   $72, $87, $87, PAT1   # b_nv
        nop
        shufb   $75, $88, $88, PAT1   # c_nv
        fma     $95, $69, $69, $95
        lqx     $92, $90, $89
        a       $125, $97, $91   # base of d_k
        rotqbyi $98, $91, 4
        rotmi   $100, $91, -4
        rotqbyi $99, $91, 8
        fa      $95, $95, ONE
        shufb   $92, ORIG, ORIG, $92   # origin in (k, u, v) order
        a       $126, $97, $98   # d_u
        lnop
        a       $127, $97, $99   # d_v
        lnop
        rotmi   $101, $98, -4
        lnop
        ai      $97, RAYS, CTX_CORNERS
        shufb   $94, $92, $92, PAT0   # o_k
        rotmi   $102, $99, -4
        shufb   $121, $92, $92, PAT1   # o_u
        nop
        lqx     $103, $97, $100   # corner d_k
        nop
        lqx     $104, $97, $101   # corner d_u
        fs      $70, $93, $94
        shufb   $122, $92, $92, PAT2   # o_v
        nop
        lqx     $105, $97, $102   # corner d_v
        nop
        frsqest $96, $95
        fma     $106, $68, $104, $103
        lnop
        fnms    $70, $68, $121, $70
        lnop
        fi      $123, $95, $96   # 1/|n|, n = (1, n_u, n_v) in (k, u, v)
        lnop
        fma     $106, $69, $105, $106   # den = n.d
        lnop
        fnms    $70, $69, $122, $70   # num = n_d - o_k - n_u o_u - n_v o_v
        lnop
        nop
        frest   $107, $106
        fi      $107, $106, $107
        lnop
        fnms    $108, $106, $107, ONE
        lnop
        fma     $107, $108, $107, $107
        lnop
        fm      $107, $70, $107   # t
        lnop
        fma     $108, $107, $104, $121   # hit u
        lnop
        fma     $109, $107, $105, $122   # hit v
        lnop
        fcgt    $113, $107, ZERO   # in front
        lnop
        fma     $110, $71, $108, $73
        lnop
        fma     $111, $74, $108, $120
        lnop
        fma     $110, $72, $109, $110   # beta
        lnop
        fma     $111, $75, $109, $111   # gamma
        lnop
        fcgt    $114, ZERO, $110
        lnop
        fa      $112, $110, $111
        lnop
        fcgt    $115, ZERO, $111
        lnop
        and     $114, $114, $113
        lnop
        and     $115, $115, $113
        lnop
        nop
        gb      $114, $114
        nop
        gb      $115, $115
        fcgt    $116, $112, ONE
        lnop
        and     $116, $116, $113
        lnop
        ceqi    $114, $114, 15   # every corner outside one edge
        gb      $113, $113
        ceqi    $115, $115, 15
        gb      $116, $116
        ceqi    $113, $113, 0   # every corner behind
        lnop
        ceqi    $116, $116, 15
        lnop
        or      $113, $113, $114
        lnop
        or      $115, $115, $116
        lnop
        or      $113, $113, $115
        lnop
        sf      S_CULLED, $113, S_CULLED   # +1 when culled
        lnop
        nop
        brnz    $113, tri_next
        ai      S_TRIS, S_TRIS, 1

        # the inside test admits barycentrics down to -2^-20 (and a sum up to 1 + 2^-20),
        # so a ray through the shared edge of two triangles hits one of them whatever
        # the truncating arithmetic makes of the edge; the nearer hit wins as usual
        lqa     $76, k_ntol
        lqa     $77, k_onetol
        # (scheduled into even/odd pairs from the 4-vector test: loads, den = n.d, t,
        # barycentrics, hit = t in (0, t_old) and inside, selb updates of t, id, n.d/|n|)
        .align  3
ray_loop:
        nop
        lqx     $65, $125, $119
        nop
        lqx     $79, $126, $119
        nop
        lqx     $81, $127, $119
        a       $82, RAYS, $119
        lnop
        nop
        lnop
        nop
        lqd     $85, CTX_RAY_T+0($82)
        ai      $119, $119, 16
        lqd     $86, CTX_RAY_T+16($82)
        fma     $87, $68, $79, $65
        lqd     $88, CTX_RAY_T+32($82)
        nop
        lqx     $89, $125, $119
        nop
        lqx     $90, $126, $119
        nop
        lqx     $91, $127, $119
        ai      $119, $119, 16
        lqd     $92, CTX_RAY_T+48($82)
        nop
        lqd     $93, CTX_RAY_ID+0($82)
        fma     $87, $69, $81, $87
        lqx     $94, $125, $119
        nop
        lqx     $95, $126, $119
        fma     $96, $68, $90, $89
        lqx     $97, $127, $119
        ai      $119, $119, 16
        lqd     $98, CTX_RAY_ND+0($82)
        nop
        lqd     $99, CTX_RAY_ID+16($82)
        nop
        lqx     $100, $125, $119
        fm      $101, $87, $123
        lqx     $102, $126, $119
        fma     $103, $68, $95, $94
        lqx     $104, $127, $119
        fma     $96, $69, $91, $96
        frest   $105, $87
        ai      $119, $119, 16
        lqd     $106, CTX_RAY_ND+16($82)
        nop
        lqd     $107, CTX_RAY_ID+32($82)
        ceqi    $112, $119, 256
        lqd     $108, CTX_RAY_ND+32($82)
        fma     $109, $68, $102, $100
        lqd     $110, CTX_RAY_ID+48($82)
        fma     $103, $69, $97, $103
        lqd     $111, CTX_RAY_ND+48($82)
        fi      $105, $87, $105
        frest   $113, $96
        fm      $114, $96, $123
        lnop
        fma     $109, $69, $104, $109
        lnop
        fi      $113, $96, $113
        frest   $115, $103
        fm      $116, $103, $123
        lnop
        fnms    $117, $87, $105, ONE
        lnop
        fi      $115, $103, $115
        lnop
        fm      $118, $109, $123
        frest   $59, $109
        fnms    $78, $96, $113, ONE
        lnop
        fma     $117, $117, $105, $105
        lnop
        fi      $59, $109, $59
        lnop
        fnms    $80, $103, $115, ONE
        lnop
        fma     $78, $78, $113, $113
        lnop
        fm      $65, $70, $117
        lnop
        fnms    $89, $109, $59, ONE
        lnop
        fma     $80, $80, $115, $115
        lnop
        fm      $94, $70, $78
        lnop
        fma     $79, $65, $79, $121
        lnop
        fma     $81, $65, $81, $122
        lnop
        fma     $89, $89, $59, $59
        lnop
        fm      $100, $70, $80
        lnop
        fcgt    $87, $85, $65
        lnop
        fma     $90, $94, $90, $121
        lnop
        fma     $96, $71, $79, $73
        lnop
        fma     $105, $74, $79, $120
        lnop
        fm      $103, $70, $89
        lnop
        fma     $95, $100, $95, $121
        lnop
        fma     $91, $94, $91, $122
        lnop
        fma     $113, $71, $90, $73
        lnop
        fma     $117, $74, $90, $120
        lnop
        fma     $97, $100, $97, $122
        lnop
        fma     $102, $103, $102, $121
        lnop
        fma     $109, $71, $95, $73
        lnop
        fma     $115, $74, $95, $120
        lnop
        fma     $104, $103, $104, $122
        lnop
        fma     $96, $72, $81, $96
        lnop
        fma     $105, $75, $81, $105
        lnop
        fma     $78, $71, $102, $73
        lnop
        fma     $59, $74, $102, $120
        lnop
        fma     $113, $72, $91, $113
        lnop
        fma     $117, $75, $91, $117
        lnop
        fma     $109, $72, $97, $109
        lnop
        fma     $115, $75, $97, $115
        lnop
        fma     $78, $72, $104, $78
        lnop
        fma     $59, $75, $104, $59
        lnop
        fa      $80, $96, $105
        lnop
        fa      $79, $113, $117
        lnop
        fcgt    $89, $76, $96
        lnop
        fa      $90, $109, $115
        lnop
        fcgt    $95, $76, $105
        lnop
        fa      $81, $78, $59
        lnop
        fcgt    $102, $76, $113
        lnop
        fcgt    $91, $76, $117
        lnop
        fcgt    $97, $76, $109
        lnop
        fcgt    $104, $76, $115
        lnop
        fcgt    $96, $76, $78
        lnop
        fcgt    $105, $76, $59
        lnop
        fcgt    $113, $80, $77
        lnop
        fcgt    $117, $65, ZERO
        lnop
        or      $89, $89, $95
        lnop
        fcgt    $109, $79, $77
        lnop
        fcgt    $115, $86, $94
        lnop
        fcgt    $78, $94, ZERO
        lnop
        or      $102, $102, $91
        lnop
        fcgt    $59, $90, $77
        lnop
        fcgt    $80, $88, $100
        lnop
        fcgt    $95, $100, ZERO
        lnop
        or      $97, $97, $104
        lnop
        fcgt    $79, $81, $77
        lnop
        fcgt    $91, $92, $103
        lnop
        fcgt    $90, $103, ZERO
        lnop
        or      $96, $96, $105
        lnop
        and     $87, $87, $117
        lnop
        or      $89, $89, $113
        lnop
        and     $115, $115, $78
        lnop
        or      $102, $102, $109
        lnop
        and     $80, $80, $95
        lnop
        or      $97, $97, $59
        hbrr    .Lray_br, ray_loop
        and     $91, $91, $90
        lnop
        or      $96, $96, $79
        lnop
        andc    $104, $87, $89
        lnop
        andc    $81, $115, $102
        lnop
        andc    $105, $80, $97
        lnop
        andc    $117, $91, $96
        lnop
        selb    $85, $85, $65, $104
        lnop
        selb    $93, $93, $124, $104
        lnop
        selb    $98, $98, $101, $104
        stqd    $85, CTX_RAY_T+0($82)
        selb    $86, $86, $94, $81
        stqd    $93, CTX_RAY_ID+0($82)
        selb    $99, $99, $124, $81
        stqd    $98, CTX_RAY_ND+0($82)
        selb    $106, $106, $114, $81
        stqd    $86, CTX_RAY_T+16($82)
        selb    $88, $88, $100, $105
        stqd    $99, CTX_RAY_ID+16($82)
        selb    $107, $107, $124, $105
        stqd    $106, CTX_RAY_ND+16($82)
        selb    $108, $108, $116, $105
        stqd    $88, CTX_RAY_T+32($82)
        selb    $92, $92, $103, $117
        stqd    $107, CTX_RAY_ID+32($82)
        selb    $110, $110, $124, $117
        stqd    $108, CTX_RAY_ND+32($82)
        selb    $111, $111, $118, $117
        stqd    $92, CTX_RAY_T+48($82)
        nop
        stqd    $110, CTX_RAY_ID+48($82)
        nop
        stqd    $111, CTX_RAY_ND+48($82)
        nop
.Lray_br:
        brz     $112, ray_loop


tri_next:
        ai      $66, $66, 1
        ai      $67, $67, -1
        brnz    $67, tri_loop
        # the packet's largest t shrinks as rays hit: refresh the IA exit bound
        
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
        br      .Lnewcur
