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
        .ifdef  EXT_MULTIHINT
        # the packet's directions as (x, y, z, 0) of base, du and dv, so that a
        # linear function of d is an affine one of (column, row), for the leaf's per-group
        # cull (triangle.s); in this context's slot of gforms (by its tag)
        lqd     $100, CTX_TAG(RAYS)
        lqa     $101, k_entry                 # (a0, b0, 0, 0)
        lqa     $102, k_pc0                   # (a0, a1, b0, 0)
        ila     $104, gforms
        ai      $100, $100, -CONTEXT_TAG0
        mpyi    $100, $100, 48
        rotqbyi $105, $76, 4
        rotqbyi $106, $74, 4
        rotqbyi $107, $75, 4
        rotqbyi $108, $76, 8
        rotqbyi $109, $74, 8
        rotqbyi $110, $75, 8
        a       $104, $104, $100
        shufb   $111, $76, $74, $101
        shufb   $112, $105, $106, $101
        shufb   $113, $108, $109, $101
        shufb   $111, $111, $75, $102
        shufb   $112, $112, $107, $102
        shufb   $113, $113, $110, $102
        lqa     $105, k_plo                   # as (x, y, z) of each (the cull's lanes
        lqa     $106, k_phi                   # are triangles, each with its own axes)
        lqa     $107, k_pc1
        lqa     $108, k_pc2
        shufb   $109, $111, $112, $105        # (base_x, base_y, du_x, du_y)
        shufb   $110, $111, $112, $106        # (dv_x, dv_y, 0, 0)
        shufb   $111, $109, $113, $102        # base
        shufb   $112, $109, $113, $107        # du
        shufb   $113, $110, $113, $108        # dv
        stqd    $111, 0($104)
        stqd    $112, 16($104)
        stqd    $113, 32($104)
        .endif

        # four vectors (two rows) per pass, scheduled into even/odd pairs
        .align  6                     # the loop starts early in a fetch line (as ray_loop)
        .sched  scratch=66-127
.Lrow:
      ! hbrr    .Lrow_br, .Lrow
        fa      $86, $89, ONE                 # the second row
        fma     $93, $89, $80, $83            # row part
        fma     $94, $89, $81, $84
        fma     $95, $89, $82, $85
        fma     $66, $86, $80, $83
        fma     $67, $86, $81, $84
        fma     $68, $86, $82, $85
        fma     $96, $91, $77, $93            # dx, dy, dz of columns 0-3
        fma     $97, $91, $78, $94
        fma     $98, $91, $79, $95
        fma     $99, $92, $77, $93            # columns 4-7
        fma     $100, $92, $78, $94
        fma     $101, $92, $79, $95
        fma     $69, $91, $77, $66
        fma     $70, $91, $78, $67
        fma     $71, $91, $79, $68
        fma     $72, $92, $77, $66
        fma     $73, $92, $78, $67
        fma     $74, $92, $79, $68
        stqd    $96, 0($88)
        stqd    $97, 256($88)
        stqd    $98, 512($88)
        stqd    $99, 16($88)
        stqd    $100, 272($88)
        stqd    $101, 528($88)
        stqd    $69, 32($88)
        stqd    $70, 288($88)
        stqd    $71, 544($88)
        stqd    $72, 48($88)
        stqd    $73, 304($88)
        stqd    $74, 560($88)
        frest   $102, $96
        frest   $103, $97
        frest   $104, $98
        frest   $105, $99
        frest   $106, $100
        frest   $107, $101
        frest   $75, $69
        frest   $76, $70
        frest   $87, $71
        frest   $119, $72
        frest   $120, $73
        frest   $121, $74
        fi      $102, $96, $102
        fi      $103, $97, $103
        fi      $104, $98, $104
        fi      $105, $99, $105
        fi      $106, $100, $106
        fi      $107, $101, $107
        fi      $75, $69, $75
        fi      $76, $70, $76
        fi      $87, $71, $87
        fi      $119, $72, $119
        fi      $120, $73, $120
        fi      $121, $74, $121
        .ifndef SHADE                         # (the eye-light grey's 1/|d|: unshaded)
        fm      $114, $96, $96                # |d|^2
        fm      $115, $99, $99
        fma     $114, $97, $97, $114
        fma     $115, $100, $100, $115
        fma     $114, $98, $98, $114
        fma     $115, $101, $101, $115
        fm      $66, $69, $69
        fm      $67, $72, $72
        fma     $66, $70, $70, $66
        fma     $67, $73, $73, $67
        fma     $66, $71, $71, $66
        fma     $67, $74, $74, $67
        .endif
        fnms    $108, $96, $102, ONE
        fnms    $109, $97, $103, ONE
        fnms    $110, $98, $104, ONE
        fnms    $111, $99, $105, ONE
        fnms    $112, $100, $106, ONE
        fnms    $113, $101, $107, ONE
        fnms    $122, $69, $75, ONE
        fnms    $123, $70, $76, ONE
        fnms    $124, $71, $87, ONE
        fnms    $125, $72, $119, ONE
        fnms    $126, $73, $120, ONE
        fnms    $127, $74, $121, ONE
        fma     $102, $108, $102, $102        # 1/d, one Newton step
        fma     $103, $109, $103, $103
        fma     $104, $110, $104, $104
        fma     $105, $111, $105, $105
        fma     $106, $112, $106, $106
        fma     $107, $113, $107, $107
        fma     $75, $122, $75, $75
        fma     $76, $123, $76, $76
        fma     $87, $124, $87, $87
        fma     $119, $125, $119, $119
        fma     $120, $126, $120, $120
        fma     $121, $127, $121, $121
        stqd    $102, 768($88)
        stqd    $103, 1024($88)
        stqd    $104, 1280($88)
        stqd    $105, 784($88)
        stqd    $106, 1040($88)
        stqd    $107, 1296($88)
        stqd    $75, 800($88)
        stqd    $76, 1056($88)
        stqd    $87, 1312($88)
        stqd    $119, 816($88)
        stqd    $120, 1072($88)
        stqd    $121, 1328($88)
        .ifndef SHADE
        frsqest $116, $114
        frsqest $117, $115
        frsqest $68, $66
        frsqest $86, $67
        fi      $116, $114, $116              # 1/|d|, ~12 bits: enough for shading
        fi      $117, $115, $117
        fi      $68, $66, $68
        fi      $86, $67, $86
        stqd    $116, 2304($88)
        stqd    $117, 2320($88)
        stqd    $68, 2336($88)
        stqd    $86, 2352($88)
        .endif
        .irp    K, 1536, 1552, 1568, 1584
        stqd    BIG, \K($88)
        .endr
        .irp    K, 1792, 1808, 1824, 1840
        stqd    $118, \K($88)
        .endr
        .ifndef SHADE
        .irp    K, 2048, 2064, 2080, 2096
        stqd    ZERO, \K($88)
        .endr
        .endif
        fa      $89, $89, ONE
        fa      $89, $89, ONE
        ai      $90, $90, -1
        ai      $88, $88, 64
.Lrow_br:
      ! brnz    $90, .Lrow
        .endsched

        # ---- packet setup, scheduled into even/odd pairs: the frustum for the IA box tests
        # (per axis the range of 1/d over the corner rays, which bounds every ray's 1/d
        # where the sign does not change), its multipliers and offsets (see trav), and the
        # first ray's data (set_first) for ray 0; then traversal from the root's children.
        # A box test computes plane * PA + OA with OA = -origin * PA - |origin * PA| * 2^-20:
        # the margin covers the rounding of the product it replaces; OA = -1e30 where the
        # directions have both signs and give no bound.
        .sched  pool=66-99,113-127 scratch=66-127
.Lsetup:
        lqd     %c0, CTX_CORNERS(RAYS)
        lqd     %c1, CTX_CORNERS+16(RAYS)
        lqd     %c2, CTX_CORNERS+32(RAYS)
        .irp    K, 0, 1, 2
        frest   %y\K, %c\K
        fi      %y\K, %c\K, %y\K
        fnms    %e\K, %c\K, %y\K, ONE
        fma     %r\K, %e\K, %y\K, %y\K
        rotqbyi %s\K, %r\K, 8
        fcgt    %m\K, %r\K, %s\K
        selb    %lo\K, %r\K, %s\K, %m\K
        selb    %hi\K, %s\K, %r\K, %m\K
        rotqbyi %lo2\K, %lo\K, 4
        rotqbyi %hi2\K, %hi\K, 4
        fcgt    %ml\K, %lo\K, %lo2\K
        fcgt    %mh\K, %hi2\K, %hi\K
        selb    %rlo\K, %lo\K, %lo2\K, %ml\K
        selb    %rhi\K, %hi\K, %hi2\K, %mh\K
        .endr
        lqa     %eps, k_eps
        lqa     %e20, k_eps20
        lqa     %abs, k_abs
        .irp    K, 0, 1, 2
        fcgt    %neg\K, ZERO, %rlo\K
        fcgt    %all\K, ZERO, %rhi\K
        andc    %mix\K, %neg\K, %all\K
        fm      %pa\K, %rlo\K, %eps
        fm      %pb\K, %rhi\K, %eps
        andc    (\K+PAX), %pa\K, %mix\K
        andc    (\K+PBX), %pb\K, %mix\K
        and     %off\K, NBIG, %mix\K
        fm      %oa\K, (\K+OXS), (\K+PAX)
        and     %oaa\K, %oa\K, %abs
        fma     %oam\K, %oaa\K, %e20, %oa\K
        fs      (\K+OAX), %off\K, %oam\K
        fm      %ob\K, (\K+OXS), (\K+PBX)
        and     %oba\K, %ob\K, %abs
        fma     %obm\K, %oba\K, %e20, %ob\K
        fs      (\K+OBX), %off\K, %obm\K
        .endr
        lqa     %odd, k_oddmask
        and     F2, NBIG, %odd
        ori     STK, STKBASE, 0
        il      FIRST, 0
        SET_FIRST
        ori     CUR, ROOTST, 0
        lqa     %empty, vars+V_EMPTY
      ! brnz    %empty, packet_done
      ! br      .Lnewcur
        .endsched
