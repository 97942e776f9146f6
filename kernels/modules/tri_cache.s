# tri_cache.s — the triangle cache's miss paths.
#
# The cache is direct mapped: TTAGS holds a 16-byte tag per line (the triangle index),
# TDATA 64-byte lines (Wald's projection record, loader::layout); the lookups are inlined
# in the leaf (modules/triangle.s). `.Lpf_miss` starts a line's DMA during the leaf's
# prefetch pass without waiting; `tri_miss` fetches one record with a blocking DMA.

        .text
.Lpf_miss:
        stqx    $76, TTAGS, $81               # the line now holds this triangle
        shli    $84, $80, 6
        a       $84, $84, TDATA
        shli    $85, $76, 6
        a       $85, $85, EATRIS
        il      $86, 1
        il      $87, 0x40
        wrch    $MFC_LSA, $84
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $85
        wrch    $MFC_Size, $79
        wrch    $MFC_TagID, $86
        wrch    $MFC_Cmd, $87
        lqa     $88, vars+V_TMISS
        il      $78, 1
        ai      $88, $88, 1
        stqa    $88, vars+V_TMISS
        br      .Lpf_next

tri_miss:
        # triangle cache miss: fetch the 64-byte record, then test it
        lqa     $86, vars+V_TMISS
        ai      $86, $86, 1
        stqa    $86, vars+V_TMISS
        stqx    $66, TTAGS, $81
        shli    $85, $66, 6
        a       $85, $85, EATRIS
        wrch    $MFC_LSA, $84
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $85
        il      $86, 64
        wrch    $MFC_Size, $86
        il      $86, 1
        wrch    $MFC_TagID, $86
        il      $86, 0x40
        wrch    $MFC_Cmd, $86
        il      $86, 2
        wrch    $MFC_WrTagMask, $86
        wrch    $MFC_WrTagUpdate, $86
        rdch    $86, $MFC_RdTagStat
        br      .Ltri_hit
