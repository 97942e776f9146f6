# bvh_cache.s — the BVH node-pair cache's miss path.
#
# The cache is direct mapped: BTAGS holds a 16-byte tag per line, BDATA 64-byte lines, and
# the lookup is inlined in the traversal step (modules/traverse.s: the pair's line is
# CUR & BMASK64, a tag that differs from CUR branches here). A miss fetches the sibling
# pair with a blocking DMA, stores it axis-major in its line (the layout traverse.s
# describes) and runs the step again.

        .text
# ---- BVH cache miss: fetch the pair, store it axis-major in its line, redo the lookup.
bvh_miss:
        lqa     $80, vars+V_BMISS
        ai      S_STEPS, S_STEPS, -1          # the step runs again
        ai      $80, $80, 1
        stqa    $80, vars+V_BMISS
        stqx    CUR, BTAGS, $72               # the line now holds this pair
        a       $80, CUR, EANODES             # the pair's effective address
        ila     $81, nodebuf
        il      $82, 64
        il      $83, 1
        il      $84, 0x40
        wrch    $MFC_LSA, $81
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $80
        wrch    $MFC_Size, $82
        wrch    $MFC_TagID, $83
        wrch    $MFC_Cmd, $84
        il      $83, 2
        wrch    $MFC_WrTagMask, $83
        wrch    $MFC_WrTagUpdate, $83
        rdch    $83, $MFC_RdTagStat
        lqd     $84, 0($81)                   # (min0, link0)
        lqd     $85, 16($81)                  # (max0, meta0)
        lqd     $86, 32($81)
        lqd     $87, 48($81)
        lqa     $88, k_plo
        lqa     $89, k_phi
        lqa     $90, k_pa
        lqa     $91, k_pb
        shufb   $92, $84, $85, $88            # (min0.x, max0.x, min0.y, max0.y)
        shufb   $93, $86, $87, $88
        shufb   $94, $84, $85, $89            # (min0.z, max0.z, link0, meta0)
        shufb   $95, $86, $87, $89
        shufb   $96, $92, $93, $90            # x planes of both children
        shufb   $97, $92, $93, $91            # y
        shufb   $98, $94, $95, $90            # z
        shufb   $99, $94, $95, $91            # (link0, meta0, link1, meta1)
        rotmi   $100, $99, -2
        ceqi    $100, $100, 0                 # lanes 1, 3: inner child
        shufb   $100, $100, $100, SWAP
        lqa     $101, k_evenmask
        and     $100, $100, $101
        shli    $101, $99, 5                  # link * 32: the child pair's byte offset
        selb    $99, $99, $101, $100
        lqa     $101, k_oddmask
        shli    $100, $99, 4                  # meta << 4: axis * 16 in bits 4-5
        selb    $99, $99, $100, $101
        a       $102, BDATA, $66
        stqd    $96, 0($102)
        stqd    $97, 16($102)
        stqd    $98, 32($102)
        stqd    $99, 48($102)
        br      trav
