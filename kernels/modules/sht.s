# sht.s — software hyperthreading (paper section 6, Algorithm 1).
#
# Each SPU keeps up to 8 packets in flight, one per packet context (the parameter block's
# SHT count; loader::kernel_abi::context: rays, stack, staging lines, saved registers, DMA
# tag CONTEXT_TAG0 + index, the next context in turn). On a cache miss the packet issues
# its DMA without waiting and is suspended: its 27 packet registers and where it resumes go
# to its context, and the next context in turn runs: its packet resumes once its own fetch
# is done (a wait on its tag, usually already over), or a new packet starts in it while
# tiles are left. The packet registers are a packet's whole state, so a switch is 27 stores,
# 27 loads and a hinted branch. With one context the miss handlers wait instead.

        .text
# a BVH miss with several contexts (the handler modules/bvh_cache.s names): fetch the pair
# into the staging line, and suspend the packet until it is there
bvh_miss_sht:
        ai      S_STEPS, S_STEPS, -1          # the step runs again
.Lb_sht_fetch:
        lqa     $80, vars+V_BMISS
        ai      $80, $80, 1
        stqa    $80, vars+V_BMISS
        a       $80, CUR, EANODES
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
        ila     $80, bvh_resume
suspend:                                      # $80: where the packet resumes
        stqd    $80, CTX_RESUME(RAYS)
        stqd    OR1X, CTX_SAVE+0(RAYS)
        stqd    OR1Y, CTX_SAVE+16(RAYS)
        stqd    OBX, CTX_SAVE+32(RAYS)
        stqd    OBY, CTX_SAVE+48(RAYS)
        stqd    OBZ, CTX_SAVE+64(RAYS)
        stqd    OR1Z, CTX_SAVE+80(RAYS)
        stqd    PAX, CTX_SAVE+96(RAYS)
        stqd    PAY, CTX_SAVE+112(RAYS)
        stqd    PAZ, CTX_SAVE+128(RAYS)
        stqd    PBX, CTX_SAVE+144(RAYS)
        stqd    PBY, CTX_SAVE+160(RAYS)
        stqd    PBZ, CTX_SAVE+176(RAYS)
        stqd    OAX, CTX_SAVE+192(RAYS)
        stqd    OAY, CTX_SAVE+208(RAYS)
        stqd    OAZ, CTX_SAVE+224(RAYS)
        stqd    F2, CTX_SAVE+240(RAYS)
        stqd    RX1, CTX_SAVE+256(RAYS)
        stqd    RY1, CTX_SAVE+272(RAYS)
        stqd    RZ1, CTX_SAVE+288(RAYS)
        stqd    PERMX, CTX_SAVE+304(RAYS)
        stqd    PERMY, CTX_SAVE+320(RAYS)
        stqd    PERMZ, CTX_SAVE+336(RAYS)
        stqd    FT_ADDR, CTX_SAVE+352(RAYS)
        stqd    FT_PAT, CTX_SAVE+368(RAYS)
        stqd    FIRST, CTX_SAVE+384(RAYS)
        stqd    CUR, CTX_SAVE+400(RAYS)
        stqd    STK, CTX_SAVE+416(RAYS)
        lqd     RAYS, CTX_NEXT(RAYS)
# switch_to: run the packet of context RAYS, once its fetch is done, or start one in it
switch_to:
        lqd     $98, CTX_RESUME(RAYS)
        lqd     $87, CTX_TAG(RAYS)            # (tag, 1 << tag)
        ila     $97, CTX_STACK
        ai      NEGTAB, RAYS, CTX_NEGTAB
        a       STKBASE, RAYS, $97
        il      $86, 2
        brz     $98, .Lempty
        hbr     .Lresume_br, $98
        rotqbyi $87, $87, 4
        wrch    $MFC_WrTagMask, $87
        wrch    $MFC_WrTagUpdate, $86
        rdch    $86, $MFC_RdTagStat
        stqd    ZERO, CTX_RESUME(RAYS)        # running
        lqd     OR1X, CTX_SAVE+0(RAYS)
        lqd     OR1Y, CTX_SAVE+16(RAYS)
        lqd     OBX, CTX_SAVE+32(RAYS)
        lqd     OBY, CTX_SAVE+48(RAYS)
        lqd     OBZ, CTX_SAVE+64(RAYS)
        lqd     OR1Z, CTX_SAVE+80(RAYS)
        lqd     PAX, CTX_SAVE+96(RAYS)
        lqd     PAY, CTX_SAVE+112(RAYS)
        lqd     PAZ, CTX_SAVE+128(RAYS)
        lqd     PBX, CTX_SAVE+144(RAYS)
        lqd     PBY, CTX_SAVE+160(RAYS)
        lqd     PBZ, CTX_SAVE+176(RAYS)
        lqd     OAX, CTX_SAVE+192(RAYS)
        lqd     OAY, CTX_SAVE+208(RAYS)
        lqd     OAZ, CTX_SAVE+224(RAYS)
        lqd     F2, CTX_SAVE+240(RAYS)
        lqd     RX1, CTX_SAVE+256(RAYS)
        lqd     RY1, CTX_SAVE+272(RAYS)
        lqd     RZ1, CTX_SAVE+288(RAYS)
        lqd     PERMX, CTX_SAVE+304(RAYS)
        lqd     PERMY, CTX_SAVE+320(RAYS)
        lqd     PERMZ, CTX_SAVE+336(RAYS)
        lqd     FT_ADDR, CTX_SAVE+352(RAYS)
        lqd     FT_PAT, CTX_SAVE+368(RAYS)
        lqd     FIRST, CTX_SAVE+384(RAYS)
        lqd     CUR, CTX_SAVE+400(RAYS)
        lqd     STK, CTX_SAVE+416(RAYS)
.Lresume_br:
        bi      $98
.Lempty:
        lqa     $86, vars+V_EXH
        brz     $86, packet_start             # tiles are left: a new packet
# sched_next: the current context has no packet and no tile is left: the next suspended
# one, if any
sched_next:
        lqa     $93, vars+V_NCTX
1:      lqd     RAYS, CTX_NEXT(RAYS)
        lqd     $98, CTX_RESUME(RAYS)
        brnz    $98, switch_to
        ai      $93, $93, -1
        brnz    $93, 1b
        br      frame_done

