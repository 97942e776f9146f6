# tri_cache.s — the triangle cache's miss paths.
#
# TTAGS holds a 16-byte tag per line (the triangle index), TDATA 64-byte lines (Wald's
# projection record, loader::layout). Direct mapped or 4-way LRU like the BVH cache
# (modules/bvh_cache.s): way 0 is looked up inline in the leaf (modules/triangle.s), whose
# prefetch pass branches to the handler for the configuration (V_PFMISS) on a miss:
#   .Lpf_one    one context: the DMA goes straight into way 0, the leaf waits once for all
#   .Lpf_ways   4-way: the other ways first (modules/lru.s), then V_PFFETCH
#   .Lpf_stage  several contexts: the record goes to the packet's staging slot and the
#               packet is suspended after the pass (modules/sht.s); when it resumes,
#               leaf_resume installs what was staged in way 0 (direct mapped: one
#               branch-free pass; 4-way: the prefetch pass again, whose .Lpf_install evicts
#               the least recent way), so no DMA in flight ever targets a cache line
# `tri_miss` serves a lookup in the test loop that misses after all (a fallback: the pass
# leaves every triangle of the leaf in the cache).
#
# The leaf's prefetch pass (modules/triangle.s) leaves a handler the missing triangle: $76
# its record index, $80 its line (index & TMASK), $81 the line's tag offset, $79 the
# record's size (64); the handler comes back to .Lpf_next with $78 = 1 (a fetch is in
# flight: the leaf waits once, after the pass).
#
# Registers of .Lpf_one (tests/src/lib.rs's module harness checks them):
#   in:       $76 $79 $80 $81 ZERO RAYS EATRIS TTAGS TDATA
#   out:      $78
#   clobbers: $84..$88 $101 $102

        .text
# back to the test loop's triangle (with EXT_MULTIHINT through .Ltri_hit_m, triangle.s,
# which computes the numerator the cull may not have)
        .macro  TRI_BACK
        .ifdef  EXT_MULTIHINT
        br      .Ltri_hit_m
        .else
        br      .Ltri_hit
        .endif
        .endm

# the staging slot of triangle $76 in the pass that began at $66: its tag's address ($89),
# its tag ($90) and its record's address ($84)
        .macro  PF_SLOT
        sf      $88, $66, $76                 # the slot
        shli    $89, $88, 4
        a       $89, $89, RAYS
        lqd     $90, CTX_STAGE_TAGS($89)
        shli    $84, $88, 6
        ila     $91, CTX_STAGE_TRIS
        a       $84, $84, $91
        a       $84, $84, RAYS
        .endm

# prefetch misses: one context fetches straight into way 0
.Lpf_one:
        a       $101, TTAGS, $81              # way 0's tag and line
        shli    $102, $80, 6
        a       $102, $102, TDATA
.Lpf_one_fetch:
        lqd     $86, CTX_TAG(RAYS)
        il      $87, 0x40
        stqd    $76, 0($101)                  # the line now holds this triangle
        ori     $84, $102, 0
.Lpf_dma:
        shli    $85, $76, 6
        a       $85, $85, EATRIS
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
.Lpf_one_evict:                               # 4-way: the least recent way goes
        il      $100, 3
        brsl    $0, lru_rotate
        br      .Lpf_one_fetch
# 4-way: the other ways of the set first
.Lpf_ways:
        a       $101, TTAGS, $81
        shli    $102, $80, 6
        a       $102, $102, TDATA
        lqa     $103, vars+V_TWAYT
        lqa     $104, vars+V_TWAYD
        ori     $116, $76, 0
        brsl    $0, lru_find
        brz     $100, 1f
        brsl    $0, lru_rotate                # in another way: now the most recent
        br      .Lpf_next
1:      lqa     $84, vars+V_PFFETCH
        bi      $84
# several contexts: a triangle staged while the packet was suspended is installed now;
# others are fetched into the packet's staging slots
        .ifdef  EXT_MULTIHINT
# (multihint) the same as two scheduled blocks, the fetch's operands and the counter's
# load before the staging check (which needs no extension)
        .sched  scratch=66-127
.Lpf_stage:
        ai      $95, $77, -1
        ila     $96, .Lpf_m_miss              # (the pass with the miss hinted taken, at
        ila     $99, leaf_probe_m             # its branch: the next triangle's tag check
        stqa    $99, pfpass                   # is done here; the next leaf's pass too)
        ila     $97, suspend
        ceqi    $95, $95, 0
        selb    $96, $96, $97, $95
      ! hbr     .Lpf_stage_br, $96
        PF_SLOT
        ai      $99, $76, 1
        and     $100, $99, TMASK
        shli    $100, $100, 4
        lqx     $103, TTAGS, $100
        ceq     $83, $103, $99
        lqd     $86, CTX_TAG(RAYS)
        il      $87, 0x40
        shli    $85, $76, 6
        a       $85, $85, EATRIS
        lqa     $98, vars+V_TMISS
        ai      $98, $98, 1
        ceq     $90, $90, $76
      ! brnz    $90, .Lpf_install
        .endsched
        .sched  scratch=66-127
        stqd    $76, CTX_STAGE_TAGS($89)
        wrch    $MFC_LSA, $84
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $85
        wrch    $MFC_Size, $79
        wrch    $MFC_TagID, $86
        wrch    $MFC_Cmd, $87
        il      $78, 1
        stqa    $98, vars+V_TMISS
        ai      $76, $76, 1
        ai      $77, $77, -1
        ila     $80, leaf_resume
.Lpf_stage_br:
      ! bi      $96
        .endsched
        .else
.Lpf_stage:
        ai      $95, $77, -1                  # the pass's step taken here, and its
        ila     $96, .Lpf                     # branch hinted to where it goes: the
        ila     $97, suspend                  # next triangle or, after the last, the
        ceqi    $95, $95, 0                   # suspension (.Lpf_suspend's, as the pass
                                              # would: a fetch is in flight)
        selb    $96, $96, $97, $95
        hbr     .Lpf_stage_br, $96
        PF_SLOT
        ceq     $90, $90, $76
        brnz    $90, .Lpf_install
        stqd    $76, CTX_STAGE_TAGS($89)
        lqd     $86, CTX_TAG(RAYS)
        il      $87, 0x40
        shli    $85, $76, 6
        a       $85, $85, EATRIS
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
        ai      $76, $76, 1
        ai      $77, $77, -1
        ila     $80, leaf_resume
.Lpf_stage_br:
        bi      $96
        .endif
.Lpf_install:                                 # (4-way, when the pass runs again)
        il      $90, -1
        stqd    $90, CTX_STAGE_TAGS($89)
        a       $101, TTAGS, $81
        shli    $102, $80, 6
        a       $102, $102, TDATA
        lqa     $90, vars+V_ASSOC4
        brz     $90, 2f
        lqa     $103, vars+V_TWAYT
        lqa     $104, vars+V_TWAYD
        il      $100, 3
        brsl    $0, lru_rotate
2:      lqd     $91, 0($84)
        lqd     $92, 16($84)
        lqd     $93, 32($84)
        lqd     $94, 48($84)
        stqd    $76, 0($101)
        stqd    $91, 0($102)
        stqd    $92, 16($102)
        stqd    $93, 32($102)
        stqd    $94, 48($102)
        br      .Lpf_next
.Lpf_suspend:
        ila     $80, leaf_resume
        br      suspend

# ---- a leaf resumed after its fetches: the staged records go to way 0 of their lines
leaf_resume:
        ori     $66, CUR, 0                   # first triangle
        rotqbyi $67, CUR, 4
        rotmi   $67, $67, -6                  # count
        lqa     $90, vars+V_ASSOC4
        brnz    $90, leaf_probe               # 4-way: the pass installs them
        ori     $76, $66, 0
        ori     $77, $67, 0
        ori     $88, RAYS, 0                  # slot j's tag at CTX_STAGE_TAGS + 16 j
        ila     $89, CTX_STAGE_TRIS           # and its record at CTX_STAGE_TRIS + 64 j
        a       $89, $89, RAYS
        il      $100, -1
# one slot of a resumed leaf's staged triangles: the cache line and the staged record
# read, the record installed where its stage tag names the triangle (its fetch came back),
# the line left as it is otherwise; then the next slot
        .macro  STAGE_INSTALL_SLOT
        and     $80, $76, TMASK
        lqd     $85, CTX_STAGE_TAGS($88)
        shli    $81, $80, 4
        shli    $82, $80, 6
        a       $83, TTAGS, $81
        a       $84, TDATA, $82
        lqd     $86, 0($83)                   # the line as it is
        lqd     $91, 0($84)
        lqd     $92, 16($84)
        lqd     $93, 32($84)
        lqd     $94, 48($84)
        lqd     $95, 0($89)                   # the staged record
        lqd     $96, 16($89)
        lqd     $97, 32($89)
        lqd     $98, 48($89)
        ceq     $99, $85, $76                 # staged: install it
        shufb   $99, $99, $99, PAT0
        selb    $86, $86, $76, $99
        selb    $91, $91, $95, $99
        selb    $92, $92, $96, $99
        selb    $93, $93, $97, $99
        selb    $94, $94, $98, $99
        stqd    $86, 0($83)
        stqd    $91, 0($84)
        stqd    $92, 16($84)
        stqd    $93, 32($84)
        stqd    $94, 48($84)
        stqd    $100, CTX_STAGE_TAGS($88)
        ai      $76, $76, 1
        ai      $88, $88, 16
        ai      $89, $89, 64
        .endm

        .ifdef  EXT_MULTIHINT
        # (multihint) one scheduled block per slot, whose way on (the next slot or, after
        # the last, the leaf's cull) is chosen as it starts and hinted in an entry of its own
        ila     $101, .Lres
        ila     $102, leaf_cull
        .sched  scratch=66-127
.Lres:
        ai      $77, $77, -1
        ceqi    $103, $77, 0
        selb    $104, $101, $102, $103
        hbr     .Lres_br, $104
        STAGE_INSTALL_SLOT
.Lres_br:
      ! bi      $104
        .endsched
        .else
        hbrr    .Lres_br, .Lres
.Lres:
        STAGE_INSTALL_SLOT
        ai      $77, $77, -1
.Lres_br:
        brnz    $77, .Lres
        br      leaf_cull
        .endif

# ---- triangle cache miss in the test loop: another way of a 4-way set, the packet's
# staging slot (fetched while it was suspended), or a fetch it waits for
tri_miss:
        a       $101, TTAGS, $81
        ori     $102, $84, 0
        lqa     $85, vars+V_ASSOC4
        brz     $85, 1f
        lqa     $103, vars+V_TWAYT
        lqa     $104, vars+V_TWAYD
        ori     $116, $66, 0
        brsl    $0, lru_find
        brz     $100, 1f
        brsl    $0, lru_rotate
        TRI_BACK
1:      brz     $85, 2f
        il      $100, 3
        brsl    $0, lru_rotate                # evict the least recent way
2:      stqd    $66, 0($101)                  # the line now holds this triangle
        sf      $88, CUR, $66                 # the staging slot (CUR: the leaf)
        shli    $89, $88, 4
        a       $89, $89, RAYS
        lqd     $90, CTX_STAGE_TAGS($89)
        ceq     $90, $90, $66
        brz     $90, .Ltm_fetch
        il      $90, -1                       # staged: install it
        stqd    $90, CTX_STAGE_TAGS($89)
        shli    $88, $88, 6
        a       $88, $88, RAYS
        lqd     $91, CTX_STAGE_TRIS($88)
        lqd     $92, CTX_STAGE_TRIS+16($88)
        lqd     $93, CTX_STAGE_TRIS+32($88)
        lqd     $94, CTX_STAGE_TRIS+48($88)
        stqd    $91, 0($84)
        stqd    $92, 16($84)
        stqd    $93, 32($84)
        stqd    $94, 48($84)
        TRI_BACK
.Ltm_fetch:
        lqa     $86, vars+V_TMISS
        ai      $86, $86, 1
        stqa    $86, vars+V_TMISS
        shli    $85, $66, 6
        a       $85, $85, EATRIS
        lqd     $87, CTX_TAG(RAYS)
        il      $86, 64
        il      $88, 0x40
        wrch    $MFC_LSA, $84
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $85
        wrch    $MFC_Size, $86
        wrch    $MFC_TagID, $87
        wrch    $MFC_Cmd, $88
        rotqbyi $86, $87, 4
        il      $88, 2
        wrch    $MFC_WrTagMask, $86
        wrch    $MFC_WrTagUpdate, $88
        rdch    $86, $MFC_RdTagStat
        TRI_BACK

