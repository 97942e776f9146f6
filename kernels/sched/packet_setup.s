.Lsetup:
lqa     %c0, corners
lqa     %c1, corners+16
lqa     %c2, corners+32
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
        rotmi   $100, FIRST, -2
        shli    $100, $100, 4                 # its vector's byte offset
        andi    $101, FIRST, 3
        shli    $101, $101, 4                 # its lane * 16
        ila     $102, ray_rx
        a       $102, $102, $100
        lqd     $103, 0($102)
        lqd     $104, 256($102)
        lqd     $105, 512($102)
        ila     $106, k_pat
        lqx     $107, $106, $101
        ila     $106, k_tpat
        lqx     FT_PAT, $106, $101
        ila     $106, ray_t
        a       FT_ADDR, $106, $100
        shufb   $103, $103, $103, $107        # 1/d splats
        shufb   $104, $104, $104, $107
        shufb   $105, $105, $105, $107
        lqa     $106, k_eps
        fm      RX1, $103, $106
        fm      RY1, $104, $106
        fm      RZ1, $105, $106
        fcgt    $108, ZERO, $103              # points down the axis
        fcgt    $109, ZERO, $104
        fcgt    $110, ZERO, $105
        lqa     $111, k_ident
        selb    PERMX, $111, SWAP, $108
        selb    PERMY, $111, SWAP, $109
        selb    PERMZ, $111, SWAP, $110
        stqd    $108, 0(NEGTAB)               # near child is child 1 when negative
        stqd    $109, 16(NEGTAB)
        stqd    $110, 32(NEGTAB)
        # OR1 = origin * RX1 + |origin * RX1| * 2^-20: plane * RX1 - OR1 is the slab
        # distance less a margin that covers the rounding of the product it replaces
        lqa     $111, k_eps20
        lqa     $112, k_abs
        fm      $103, OXS, RX1
        fm      $104, OYS, RY1
        fm      $105, OZS, RZ1
        and     $106, $103, $112
        and     $107, $104, $112
        and     $108, $105, $112
        fma     OR1X, $106, $111, $103
        fma     OR1Y, $107, $111, $104
        fma     OR1Z, $108, $111, $105
ori     CUR, ROOTST, 0
lqa     %empty, vars+V_EMPTY
! brnz    %empty, packet_done
! br      .Lnewcur
