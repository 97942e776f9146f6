# raygen.s — ray generation and packet setup for one 8x8 packet of primary rays.
#
# The packet's rays (row-major, ray i = row*8 + col) are written to the current packet
# context (RAYS: ray_dx/dy/dz, then the reciprocals ray_rx/ry/rz, see
# loader::kernel_abi::context), four vectors (two rows) per pass; t starts at 1e30 and the
# hit id at -1. The packet setup then builds the frustum of the corner rays for the
# interval-arithmetic box tests (PA*, PB*, OA*, OB*, F2), the first ray's data, and enters
# traversal (modules/traverse.s) at the root's children.

        .text
packet_loop:
        # ---- ray generation: d = dir00 + (px0 + col)*du + (py0 + row)*dv
        lqa     $66, vars+V_CURPKT
        lqa     $67, vars+V_TX
        lqa     $68, vars+V_TY
        lqa     $73, vars+V_DIR00
        lqa     $74, vars+V_DU
        lqa     $75, vars+V_DV
        andi    $69, $66, 7
        rotmi   $70, $66, -3
        shli    $71, $67, 6
        shli    $72, $68, 6
        shli    $69, $69, 3
        shli    $70, $70, 3
        a       $69, $69, $71                 # px0
        a       $70, $70, $72                 # py0
        csflt   $69, $69, 0
        csflt   $70, $70, 0
        shufb   $69, $69, $69, PAT0
        shufb   $70, $70, $70, PAT0
        shufb   $77, $74, $74, PAT0           # du, dv splats
        shufb   $78, $74, $74, PAT1
        fma     $76, $69, $74, $73
        shufb   $79, $74, $74, PAT2
        shufb   $80, $75, $75, PAT0
        fma     $76, $70, $75, $76            # base direction (x, y, z, 0)
        shufb   $81, $75, $75, PAT1
        shufb   $82, $75, $75, PAT2
        lqa     $86, k_ccol
        lqa     $87, k_crow
        shufb   $83, $76, $76, PAT0           # base x, y, z splats
        shufb   $84, $76, $76, PAT1
        shufb   $85, $76, $76, PAT2
        lqa     $91, k_colf0
        lqa     $92, k_colf1
        # corner rays (0, 7, 56, 63) for the packet frustum
        fma     $93, $87, $80, $83
        fma     $94, $87, $81, $84
        fma     $95, $87, $82, $85
        ori     $88, RAYS, 0                  # vector pointer
        il      $89, 0                        # row (float)
        fma     $93, $86, $77, $93
        fma     $94, $86, $78, $94
        fma     $95, $86, $79, $95
        il      $90, 4                        # row pairs left
        il      $118, -1
        stqd    $93, CTX_CORNERS(RAYS)
        stqd    $94, CTX_CORNERS+16(RAYS)
        stqd    $95, CTX_CORNERS+32(RAYS)

        # four vectors (two rows) per pass, scheduled into even/odd pairs
        .align  3
.Lrow:
        fa      $86, $89, ONE   # the second row
        hbrr    .Lrow_br, .Lrow
        fma     $93, $89, $80, $83   # row part
        lnop
        fma     $94, $89, $81, $84
        lnop
        fma     $95, $89, $82, $85
        lnop
        fa      $89, $89, ONE
        lnop
        ai      $90, $90, -1
        lnop
        fma     $66, $86, $80, $83
        lnop
        fma     $67, $86, $81, $84
        lnop
        fma     $68, $86, $82, $85
        lnop
        fma     $96, $91, $77, $93   # dx, dy, dz of columns 0-3
        lnop
        fma     $97, $91, $78, $94
        lnop
        fma     $98, $91, $79, $95
        lnop
        fma     $99, $92, $77, $93   # columns 4-7
        lnop
        fma     $100, $92, $78, $94
        lnop
        fma     $101, $92, $79, $95
        lnop
        fma     $69, $91, $77, $66
        frest   $102, $96
        fma     $70, $91, $78, $67
        frest   $103, $97
        fma     $71, $91, $79, $68
        frest   $104, $98
        fma     $72, $92, $77, $66
        frest   $105, $99
        fma     $73, $92, $78, $67
        frest   $106, $100
        fma     $74, $92, $79, $68
        frest   $107, $101
        fi      $102, $96, $102
        stqd    $96, 0($88)
        fi      $103, $97, $103
        stqd    $97, 256($88)
        fi      $104, $98, $104
        stqd    $98, 512($88)
        fi      $105, $99, $105
        stqd    $99, 16($88)
        fi      $106, $100, $106
        stqd    $100, 272($88)
        fi      $107, $101, $107
        stqd    $101, 528($88)
        fm      $114, $96, $96   # |d|^2
        stqd    $69, 32($88)
        fm      $115, $99, $99
        stqd    $70, 288($88)
        fm      $66, $69, $69
        stqd    $71, 544($88)
        fm      $67, $72, $72
        frest   $75, $69
        fnms    $108, $96, $102, ONE
        frest   $76, $70
        fnms    $109, $97, $103, ONE
        frest   $87, $71
        fma     $114, $97, $97, $114
        frest   $119, $72
        fi      $75, $69, $75
        frest   $120, $73
        fi      $76, $70, $76
        frest   $121, $74
        fi      $87, $71, $87
        stqd    $72, 48($88)
        fi      $119, $72, $119
        stqd    $73, 304($88)
        fi      $120, $73, $120
        stqd    $74, 560($88)
        fi      $121, $74, $121
        lnop
        fma     $115, $100, $100, $115
        lnop
        fma     $66, $70, $70, $66
        lnop
        fma     $67, $73, $73, $67
        lnop
        fnms    $110, $98, $104, ONE
        lnop
        fnms    $111, $99, $105, ONE
        lnop
        fnms    $112, $100, $106, ONE
        lnop
        fnms    $113, $101, $107, ONE
        lnop
        fnms    $122, $69, $75, ONE
        lnop
        fnms    $123, $70, $76, ONE
        lnop
        fnms    $124, $71, $87, ONE
        lnop
        fnms    $125, $72, $119, ONE
        lnop
        fnms    $126, $73, $120, ONE
        lnop
        fnms    $127, $74, $121, ONE
        lnop
        fma     $114, $98, $98, $114
        lnop
        fma     $115, $101, $101, $115
        lnop
        fma     $66, $71, $71, $66
        lnop
        fma     $67, $74, $74, $67
        lnop
        fma     $102, $108, $102, $102   # 1/d, one Newton step
        lnop
        fma     $103, $109, $103, $103
        lnop
        fma     $104, $110, $104, $104
        frsqest $116, $114
        fma     $105, $111, $105, $105
        frsqest $117, $115
        fma     $106, $112, $106, $106
        frsqest $68, $66
        fma     $107, $113, $107, $107
        frsqest $86, $67
        fma     $75, $122, $75, $75
        lnop
        fma     $76, $123, $76, $76
        lnop
        fma     $87, $124, $87, $87
        lnop
        fma     $119, $125, $119, $119
        lnop
        fma     $120, $126, $120, $120
        lnop
        fma     $121, $127, $121, $121
        lnop
        fi      $116, $114, $116   # 1/|d|, ~12 bits: enough for shading
        stqd    $102, 768($88)
        fi      $117, $115, $117
        stqd    $103, 1024($88)
        fi      $68, $66, $68
        stqd    $104, 1280($88)
        fi      $86, $67, $86
        stqd    $105, 784($88)
        fa      $89, $89, ONE
        stqd    $106, 1040($88)
        nop
        stqd    $107, 1296($88)
        nop
        stqd    $75, 800($88)
        nop
        stqd    $76, 1056($88)
        nop
        stqd    $87, 1312($88)
        nop
        stqd    $119, 816($88)
        nop
        stqd    $120, 1072($88)
        nop
        stqd    $121, 1328($88)
        nop
        stqd    $116, 2304($88)
        nop
        stqd    $117, 2320($88)
        nop
        stqd    $68, 2336($88)
        nop
        stqd    $86, 2352($88)
        nop
        stqd    BIG, 1536($88)
        nop
        stqd    BIG, 1552($88)
        nop
        stqd    BIG, 1568($88)
        nop
        stqd    BIG, 1584($88)
        nop
        stqd    $118, 1792($88)
        nop
        stqd    $118, 1808($88)
        nop
        stqd    $118, 1824($88)
        nop
        stqd    $118, 1840($88)
        nop
        stqd    ZERO, 2048($88)
        nop
        stqd    ZERO, 2064($88)
        nop
        stqd    ZERO, 2080($88)
        nop
        stqd    ZERO, 2096($88)
        ai      $88, $88, 64
        lnop
        nop
.Lrow_br:
        brnz    $90, .Lrow

        # ---- packet setup, scheduled into even/odd pairs: the frustum for the IA box tests
        # (per axis the range of 1/d over the corner rays, which bounds every ray's 1/d
        # where the sign does not change), its multipliers and offsets (see trav), and the
        # first ray's data (set_first) for ray 0; then traversal from the root's children.
        # A box test computes plane * PA + OA with OA = -origin * PA - |origin * PA| * 2^-20:
        # the margin covers the rounding of the product it replaces; OA = -1e30 where the
        # directions have both signs and give no bound.
        .align  3
.Lsetup:
        il      FIRST, 0
        lqd     $66, CTX_CORNERS(RAYS)
        ila     $106, k_pat
        lqd     $67, CTX_CORNERS+16(RAYS)
        andi    $101, FIRST, 3
        lqd     $68, CTX_CORNERS+32(RAYS)
        rotmi   $100, FIRST, -2
        lqa     $69, k_eps
        shli    $101, $101, 4   # its lane * 16
        lqa     $70, k_abs
        nop
        lqa     $71, k_eps20
        ori     STK, STKBASE, 0
        frest   $72, $66
        shli    $100, $100, 4   # its vector's byte offset
        frest   $73, $67
        nop
        frest   $74, $68
        nop
        lqx     $107, $106, $101
        fi      $72, $66, $72
        lqa     $75, k_oddmask
        fi      $73, $67, $73
        lqa     $111, k_ident
        fi      $74, $68, $74
        lnop
        ila     $106, k_tpat
        lnop
        a       $102, RAYS, $100
        lnop
        nop
        lqx     FT_PAT, $106, $101
        nop
        lqd     $103, CTX_RAY_RX($102)
        fnms    $76, $66, $72, ONE
        lqd     $104, CTX_RAY_RX+256($102)
        fnms    $77, $67, $73, ONE
        lqd     $105, CTX_RAY_RX+512($102)
        fnms    $78, $68, $74, ONE
        lnop
        a       FT_ADDR, RAYS, $100
        lnop
        and     F2, NBIG, $75
        lqa     $106, k_eps
        nop
        shufb   $103, $103, $103, $107   # 1/d splats
        fma     $79, $76, $72, $72
        shufb   $104, $104, $104, $107
        fma     $80, $77, $73, $73
        shufb   $105, $105, $105, $107
        fma     $81, $78, $74, $74
        lnop
        fcgt    $108, ZERO, $103   # points down the axis
        lnop
        fm      RX1, $103, $106
        lnop
        fm      RY1, $104, $106
        lnop
        fm      RZ1, $105, $106
        rotqbyi $82, $79, 8
        fcgt    $109, ZERO, $104
        rotqbyi $83, $80, 8
        fcgt    $110, ZERO, $105
        rotqbyi $84, $81, 8
        selb    PERMX, $111, SWAP, $108
        lnop
        fcgt    $85, $79, $82
        lnop
        fcgt    $86, $80, $83
        lnop
        fcgt    $87, $81, $84
        lnop
        selb    $88, $79, $82, $85
        lnop
        selb    $89, $82, $79, $85
        lnop
        selb    $90, $80, $83, $86
        rotqbyi $91, $88, 4
        selb    $92, $83, $80, $86
        rotqbyi $93, $89, 4
        selb    $94, $81, $84, $87
        rotqbyi $95, $90, 4
        selb    $96, $84, $81, $87
        rotqbyi $97, $92, 4
        fcgt    $98, $88, $91
        rotqbyi $99, $94, 4
        fcgt    $113, $93, $89
        rotqbyi $114, $96, 4
        fcgt    $115, $90, $95
        lnop
        fcgt    $116, $97, $92
        lnop
        fcgt    $117, $94, $99
        lnop
        fcgt    $118, $114, $96
        lnop
        selb    $119, $88, $91, $98
        lnop
        selb    $120, $89, $93, $113
        lnop
        selb    $121, $90, $95, $115
        lnop
        selb    $122, $92, $97, $116
        lnop
        selb    $123, $94, $99, $117
        lnop
        selb    $124, $96, $114, $118
        lnop
        fm      $125, $119, $69
        lnop
        fm      $126, $120, $69
        lnop
        fm      $127, $121, $69
        lnop
        fm      $66, $122, $69
        lnop
        fm      $67, $123, $69
        lnop
        fm      $68, $124, $69
        lnop
        fcgt    $75, ZERO, $119
        lnop
        fcgt    $72, ZERO, $120
        lnop
        fcgt    $76, ZERO, $121
        lnop
        fcgt    $73, ZERO, $122
        lnop
        fcgt    $77, ZERO, $123
        lnop
        fcgt    $74, ZERO, $124
        lnop
        andc    $78, $75, $72
        lnop
        andc    $79, $76, $73
        lnop
        andc    $82, $77, $74
        lnop
        andc    $43, $125, $78
        lnop
        andc    $46, $126, $78
        lnop
        andc    $44, $127, $79
        lnop
        andc    $47, $66, $79
        lnop
        andc    $45, $67, $82
        lnop
        andc    $48, $68, $82
        lnop
        fm      $85, $33, $43
        lnop
        fm      $86, $33, $46
        lnop
        fm      $80, $34, $44
        lnop
        fm      $83, $34, $47
        lnop
        fm      $87, $35, $45
        lnop
        fm      $84, $35, $48
        lnop
        and     $81, $85, $70
        lnop
        and     $91, $86, $70
        lnop
        and     $88, $80, $70
        lnop
        and     $98, $83, $70
        lnop
        and     $89, $87, $70
        lnop
        and     $113, $84, $70
        lnop
        fma     $93, $81, $71, $85
        lnop
        fma     $90, $91, $71, $86
        lnop
        fma     $95, $88, $71, $80
        lnop
        fma     $115, $98, $71, $83
        lnop
        fma     $92, $89, $71, $87
        lnop
        fma     $97, $113, $71, $84
        lnop
        and     $116, NBIG, $78
        lnop
        and     $94, NBIG, $79
        lnop
        and     $117, NBIG, $82
        lnop
        fs      $49, $116, $93
        lnop
        fs      $27, $116, $90
        lnop
        fs      $50, $94, $95
        lnop
        fs      $28, $94, $115
        lnop
        fs      $51, $117, $92
        lnop
        fs      $29, $117, $97
        lnop
        selb    PERMY, $111, SWAP, $109
        lnop
        selb    PERMZ, $111, SWAP, $110
        lnop
        fm      $103, OXS, RX1
        stqd    $108, 0(NEGTAB)   # near child is child 1 when negative
        fm      $104, OYS, RY1
        stqd    $109, 16(NEGTAB)
        fm      $105, OZS, RZ1
        stqd    $110, 32(NEGTAB)
        ori     CUR, ROOTST, 0
        lqa     $112, k_abs
        nop
        lqa     $111, k_eps20
        nop
        lqa     $99, vars+V_EMPTY
        and     $106, $103, $112
        lnop
        and     $107, $104, $112
        lnop
        and     $108, $105, $112
        lnop
        fma     OR1X, $106, $111, $103
        lnop
        fma     OR1Y, $107, $111, $104
        lnop
        fma     OR1Z, $108, $111, $105
        lnop
        nop
        brnz    $99, packet_done
        nop
        br      .Lnewcur
