# bvh_cache.s — the BVH node-pair cache's miss paths.
#
# BTAGS holds a 16-byte tag per line, BDATA 64-byte lines. The cache is direct mapped or
# 4-way set-associative with LRU replacement (the parameter block's associativity): a 4-way
# cache keeps its ways as four direct-mapped quarters of S = lines/4 sets (way w of set s
# is line w*S + s), ordered by their last use, so its most recent way is looked up exactly
# like a direct-mapped line, inlined in the traversal step (modules/traverse.s: the pair's
# line is CUR & BMASK64; a tag that differs from CUR branches to BMISSH, the handler the
# frame driver chose for the configuration). Each handler is a straight line:
#   bvh_miss_one   direct mapped, one context: fetch the pair, wait, install it
#   bvh_miss_ways  4-way: the other ways of the set (a hit there moves it to the front,
#                  modules/lru.s), else the fetch of the configuration (V_BFETCH)
#   bvh_miss_sht   several contexts (modules/sht.s): fetch and suspend the packet
# A pair is fetched into the context's staging line and stored axis-major (the layout
# traverse.s describes) in way 0 when the packet runs again, evicting the least recent way
# of a 4-way set; the step then runs again.
#
# The step (modules/traverse.s) leaves the lookup it made to the handler: $66 = CUR &
# BMASK64, the pair's line offset in BDATA, and $72 = $66 / 4, its tag's offset in BTAGS;
# the handler fetches the pair CUR (EANODES + CUR) on the context's tag (RAYS) and goes
# back to `trav`, one step less counted (the step counts again).
#
# Registers of bvh_miss_one (tests/src/lib.rs's module harness checks them):
#   in:       $66 $72 ZERO CUR RAYS EANODES BTAGS BDATA SWAP S_STEPS
#   out:      S_STEPS
#   clobbers: $80..$102

        .text
# ---- BVH cache miss. A 4-way cache looks in the other ways of the set first (a hit there
# becomes the most recent way); otherwise the pair is fetched into the context's staging
# line. One context waits for it; with more, the packet is suspended and another runs
# (software hyperthreading), and the line is installed when it resumes: the cache only
# changes while a packet runs, so no fetch in flight can land in a line another packet
# has taken over meanwhile.
bvh_miss_one:                                 # direct mapped, one context
        ai      S_STEPS, S_STEPS, -1          # the step runs again
        a       $101, BTAGS, $72              # way 0's tag and line
        a       $102, BDATA, $66
.Lb_one_fetch:
        lqa     $80, vars+V_BMISS
        ai      $80, $80, 1
        stqa    $80, vars+V_BMISS
        a       $80, CUR, EANODES             # the pair's effective address
        ila     $81, CTX_STAGE_PAIR
        a       $81, $81, RAYS
        il      $82, 64
        lqd     $83, CTX_TAG(RAYS)
        il      $84, 0x40
        wrch    $MFC_LSA, $81
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $80
        wrch    $MFC_Size, $82
        wrch    $MFC_TagID, $83
        wrch    $MFC_Cmd, $84
        rotqbyi $84, $83, 4
        il      $85, 2
        wrch    $MFC_WrTagMask, $84
        wrch    $MFC_WrTagUpdate, $85
        rdch    $85, $MFC_RdTagStat
        lqa     $80, vars+V_ASSOC4
        brnz    $80, .Lb_evict
# store the staged pair axis-major in way 0
.Lb_way0:
        hbrr    .Lb_trav_br, trav
        stqd    CUR, 0($101)                  # the line now holds this pair
        ori     $81, RAYS, 0
        lqd     $84, CTX_STAGE_PAIR($81)                   # (min0, link0)
        lqd     $85, CTX_STAGE_PAIR+16($81)                  # (max0, meta0)
        lqd     $86, CTX_STAGE_PAIR+32($81)
        lqd     $87, CTX_STAGE_PAIR+48($81)
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
        stqd    $96, 0($102)
        stqd    $97, 16($102)
        stqd    $98, 32($102)
        stqd    $99, 48($102)
.Lb_trav_br:
        br      trav
.Lb_evict:                                    # 4-way: evict the least recent way
        lqa     $103, vars+V_BWAYT
        lqa     $104, vars+V_BWAYD
        il      $100, 3
        brsl    $0, lru_rotate
        br      .Lb_way0

# 4-way: the other ways of the set first; a hit there becomes the most recent way
bvh_miss_ways:
        ai      S_STEPS, S_STEPS, -1
        a       $101, BTAGS, $72
        a       $102, BDATA, $66
        lqa     $103, vars+V_BWAYT
        lqa     $104, vars+V_BWAYD
        ori     $116, CUR, 0
        brsl    $0, lru_find
        brz     $100, 1f
        brsl    $0, lru_rotate
        br      trav
1:      lqa     $80, vars+V_BFETCH
        bi      $80

# resumed with the pair in the staging line: another packet may have cached it meanwhile
bvh_resume:
        hbrr    .Lb_res_br, .Lb_way0
        and     $66, CUR, BMASK64
        rotmi   $72, $66, -2
        a       $101, BTAGS, $72
        a       $102, BDATA, $66
        lqd     $80, 0($101)
        lqa     $81, vars+V_ASSOC4
        ceq     $80, $80, CUR
        brnz    $80, trav
        brnz    $81, .Lb_rways
.Lb_res_br:
        br      .Lb_way0
.Lb_rways:
        lqa     $103, vars+V_BWAYT
        lqa     $104, vars+V_BWAYD
        ori     $116, CUR, 0
        brsl    $0, lru_find
        brz     $100, .Lb_evict
        brsl    $0, lru_rotate
        br      trav

