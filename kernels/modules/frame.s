# frame.s — the frame driver: start-up and the tile loop.
#
# Host protocol (loader::runtime): $3 = SPU index, $4 = effective address of the 128-byte
# parameter block (PARAM_*). `_start` fetches the parameters, sets the frame constants,
# carves the caches (direct mapped or 4-way, modules/bvh_cache.s) and the packet contexts
# (loader::kernel_abi::context; one per packet in flight, modules/sht.s), and picks the
# miss handlers for the configuration. `packet_start` gives the current context the next
# packet of the tile (`next_tile` takes 64x64 tiles from a shared counter with an atomic
# getllar/putllc increment, made two packets before the tile's end by `claim_ahead` so that
# its outcome is not waited for) and falls into ray generation (modules/raygen.s); packet output
# (modules/output.s) comes back here for the context's next packet; a context without a
# packet, once no tile is left, goes to sched_next. The end of the frame, `frame_done`, is
# in modules/frame_done.s: it stays the last block of the program so the hot code keeps
# its addresses.

        .text
        .global _start
_start:
        il      ZERO, 0
        stqa    $3, vars+V_MYID
        # fetch the parameter block
        ila     $66, params
        il      $67, 128
        il      $68, 0
        wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $4
        wrch    $MFC_Size, $67
        wrch    $MFC_TagID, $68
        il      $69, 0x40
        wrch    $MFC_Cmd, $69
        il      $69, 1
        wrch    $MFC_WrTagMask, $69
        il      $69, 2
        wrch    $MFC_WrTagUpdate, $69
        rdch    $69, $MFC_RdTagStat

        # constants
        ilhu    ONE, 0x3f80
        ilhu    BIG, 0x7149
        iohl    BIG, 0xf2ca
        ilhu    NBIG, 0xf149
        iohl    NBIG, 0xf2ca
        ila     $66, k_pat
        lqd     PAT0, 0($66)
        lqd     PAT1, 16($66)
        lqd     PAT2, 32($66)
        lqd     PAT3, 48($66)
        lqa     $75, k_m3
        lqa     SWAP, k_swap
        ilhu    SIGNS, 0x8000
        lqa     NEGODD, k_negodd
        nop
        nop

        # parameters
        ila     $66, params
        lqd     $67, PARAM_EA_NODES($66)      # quad 0: nodes, tris, fb, counter
        ori     EANODES, $67, 0
        rotqbyi EATRIS, $67, 4
        rotqbyi $68, $67, 8
        stqa    $68, vars+V_EAFB
        rotqbyi $68, $67, 12
        stqa    $68, vars+V_EACNT
        lqd     $67, PARAM_WIDTH($66)         # quad 1: width, height, tiles_x, num_tiles
        rotqbyi $68, $67, 8
        stqa    $68, vars+V_TILESX
        rotqbyi $68, $67, 12
        stqa    $68, vars+V_NTILES
        lqd     ORIG, PARAM_ORIGIN($66)
        lqd     $68, PARAM_DIR00($66)
        lqd     $69, PARAM_DU($66)
        lqd     $70, PARAM_DV($66)
        andc    ORIG, ORIG, $75
        andc    $68, $68, $75
        andc    $69, $69, $75
        andc    $70, $70, $75
        stqa    $68, vars+V_DIR00
        stqa    $69, vars+V_DU
        stqa    $70, vars+V_DV
        shufb   OXS, ORIG, ORIG, PAT0
        shufb   OYS, ORIG, ORIG, PAT1
        shufb   OZS, ORIG, ORIG, PAT2
        lqd     $67, PARAM_BVH_LOG2($66)      # quad 6: bvh log2, tri log2, stats EA
        rotqbyi $68, $67, 8
        stqa    $68, vars+V_EASTATS
        # carve the caches: lines = 1 << log2. A 4-way cache keeps its ways as four
        # direct-mapped quarters of S = lines/4 sets (way w of set s is line w*S + s), the
        # most recently used first, so a hit in way 0 is the direct-mapped hit path
        lqd     $76, PARAM_SHT($66)           # quad 7: packet contexts, ways
        il      $69, 1
        shl     $70, $69, $67                 # BVH lines
        rotqbyi $71, $67, 4
        shl     $71, $69, $71                 # triangle lines
        rotqbyi $77, $76, 4
        ceqi    $78, $77, 4
        stqa    $78, vars+V_ASSOC4
        andi    $79, $78, 2                   # log2 of the ways
        sfi     $81, $79, 0
        rotm    $80, $70, $81                 # BVH sets
        rotm    $82, $71, $81                 # triangle sets
        ai      BMASK64, $80, -1
        shli    BMASK64, BMASK64, 6
        ai      TMASK, $82, -1
        shli    $83, $80, 4
        stqa    $83, vars+V_BWAYT
        shli    $83, $80, 6
        stqa    $83, vars+V_BWAYD
        shli    $83, $82, 4
        stqa    $83, vars+V_TWAYT
        shli    $83, $82, 6
        stqa    $83, vars+V_TWAYD
        ila     BTAGS, cache_area
        shli    $72, $70, 4
        a       BDATA, BTAGS, $72
        ai      BDATA16, BDATA, 16
        ai      BDATA32, BDATA, 32
        ai      BDATA48, BDATA, 48
        shli    $72, $70, 6
        a       TTAGS, BDATA, $72
        shli    $72, $71, 4
        a       TDATA, TTAGS, $72
        # the packet contexts follow: none suspended, nothing staged
        shli    $72, $71, 6
        a       $84, TDATA, $72
        stqa    $84, vars+V_CTX0
        stqa    $76, vars+V_NCTX
        ceqi    $85, $76, 1
        stqa    $85, vars+V_NCTX1
        # the miss handlers: one per configuration, each a straight line
        ila     $86, .Lb_sht_fetch
        ila     $87, .Lb_one_fetch
        selb    $86, $86, $87, $85
        stqa    $86, vars+V_BFETCH
        ila     $86, bvh_miss_sht
        ila     $87, bvh_miss_one
        selb    $86, $86, $87, $85
        ila     $87, bvh_miss_ways
        selb    BMISSH, $86, $87, $78
        stqa    BMISSH, vars+V_BMISSH
        ila     $86, .Lpf_stage
        ila     $87, .Lpf_one_evict
        selb    $86, $86, $87, $85
        stqa    $86, vars+V_PFFETCH
        ila     $86, .Lpf_stage
        ila     $87, .Lpf_one
        selb    $86, $86, $87, $85
        ila     $87, .Lpf_ways
        selb    $86, $86, $87, $78
        stqa    $86, vars+V_PFMISS
        il      $72, -1
        ori     $86, $76, 0
        ai      $87, $84, CTX_HEADER
        il      $88, CTX_BYTES
        il      $89, CONTEXT_TAG0
        il      $90, 1
        lqa     $91, k_entry
1:      stqd    ZERO, CTX_RESUME($87)
        .irp    J, 0, 1, 2, 3, 4, 5, 6, 7
        stqd    $72, CTX_STAGE_TAGS+\J*16($87)
        .endr
        shl     $92, $90, $89
        shufb   $92, $89, $92, $91            # (tag, 1 << tag)
        stqd    $92, CTX_TAG($87)
        ai      $89, $89, 1
        a       $93, $87, $88
        ai      $86, $86, -1
        ai      $94, $84, CTX_HEADER          # the last one's next is the first
        ceqi    $95, $86, 0
        selb    $93, $93, $94, $95
        stqd    $93, CTX_NEXT($87)
        ori     $87, $93, 0
        brnz    $86, 1b
        # invalidate every tag of both caches
        il      $72, -1
        ori     $73, BTAGS, 0
1:      stqd    $72, 0($73)
        ai      $73, $73, 16
        ai      $70, $70, -1
        brnz    $70, 1b
        ori     $73, TTAGS, 0
1:      stqd    $72, 0($73)
        ai      $73, $73, 16
        ai      $71, $71, -1
        brnz    $71, 1b
        # the reserved quarter of both output blocks stays zero
        ila     $73, outbuf+768
        il      $74, 16
1:      stqd    ZERO, 0($73)
        stqd    ZERO, 1024($73)
        ai      $73, $73, 16
        ai      $74, $74, -1
        brnz    $74, 1b

        # the root node as a traversal state (link', meta, 0, 0); an inner root whose link
        # is 0 marks the empty scene (see loader::layout)
        ila     $66, nodebuf
        il      $67, 32
        wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, EANODES
        wrch    $MFC_Size, $67
        wrch    $MFC_TagID, ZERO
        il      $67, 0x40
        wrch    $MFC_Cmd, $67
        il      $67, 1
        wrch    $MFC_WrTagMask, $67
        il      $67, 2
        wrch    $MFC_WrTagUpdate, $67
        rdch    $67, $MFC_RdTagStat
        lqd     $67, 0($66)
        lqd     $68, 16($66)
        lqa     $69, k_root
        shufb   $70, $67, $68, $69            # (link, meta, 0, 0)
        rotqbyi $71, $70, 4
        rotmi   $71, $71, -2                  # triangle count
        ceqi    $72, $71, 0                   # inner
        shli    $73, $70, 5                   # child-pair byte offset
        lqa     $74, k_word0
        and     $72, $72, $74                 # lane 0 only
        ceqi    $75, $70, 0                   # link 0 ...
        and     $75, $75, $72                 # ... of an inner root: empty
        stqa    $75, vars+V_EMPTY
        selb    ROOTST, $70, $73, $72
        lqa     $74, k_word1
        shli    $73, ROOTST, 4                # meta << 4: axis * 16 in bits 4-5
        selb    ROOTST, ROOTST, $73, $74

        # statistics
        il      S_STEPS, 0
        il      M1V, 0
        il      EEV, 0
        il      S_TRIS, 0
        il      S_CULLED, 0
        il      S_TLOOK, 0
        stqa    ZERO, vars+V_BMISS
        stqa    ZERO, vars+V_TMISS
        stqa    ZERO, vars+V_LEAVES
        stqa    ZERO, vars+V_PACKETS
        stqa    ZERO, vars+V_OUTSEL

        stqa    ZERO, vars+V_EXH
        il      $66, 64
        stqa    $66, vars+V_PKT               # no tile yet
        lqa     RAYS, vars+V_CTX0             # the first packet context
        ai      RAYS, RAYS, CTX_HEADER
        ai      NEGTAB, RAYS, CTX_NEGTAB
        ila     $97, CTX_STACK
        a       STKBASE, RAYS, $97
        br      packet_start

# ---- the current tile is done: take the next one, if any
new_tile:
        lqa     $66, vars+V_EXH
        brnz    $66, sched_next               # no tile left: the context stays empty

# the tile counter's line (EA $70) to lockbuf ($66) with a reservation, the counter's
# value to $71, the value + $69 put back conditionally (putllc); its status is left unread
        .macro  TILE_CLAIM
        wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $70
        il      $67, 0xd0                     # getllar
        wrch    $MFC_Cmd, $67
        rdch    $68, $MFC_RdAtomicStat
        lqd     $71, 0($66)
        a       $72, $71, $69
        stqd    $72, 0($66)
        wrch    $MFC_LSA, $66
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $70
        il      $67, 0xb4                     # putllc
        wrch    $MFC_Cmd, $67
        .endm

# ---- take the next tile: atomic fetch-and-increment of the shared counter. The claim
# made ahead (claim_ahead) is taken if its putllc held; otherwise, or without one, the
# getllar/putllc loop runs here.
next_tile:
        ila     $66, lockbuf
        lqa     $69, k_inc0
        lqa     $70, vars+V_EACNT
        lqa     $71, vars+V_PENDING
        brz     $71, 2f
        stqa    ZERO, vars+V_PENDING
        rdch    $68, $MFC_RdAtomicStat        # the claim ahead's putllc
        andi    $68, $68, 1
        lqa     $71, vars+V_AHEAD
        brz     $68, 5f                       # it held: its tile
2:      TILE_CLAIM
        rdch    $68, $MFC_RdAtomicStat
        andi    $68, $68, 1
        brnz    $68, 2b                       # reservation lost: retry
5:
        lqa     $73, vars+V_NTILES
        clgt    $68, $73, $71
        brz     $68, no_tiles
        stqa    $71, vars+V_TILE
        # tile coordinates: TY = TILE / TILESX, TX = TILE % TILESX (few tiles per row)
        lqa     $74, vars+V_TILESX
        il      $75, 0
        ori     $76, $71, 0
3:      clgt    $68, $74, $76
        brnz    $68, 4f
        sf      $76, $74, $76
        ai      $75, $75, 1
        br      3b
4:      stqa    $76, vars+V_TX
        stqa    $75, vars+V_TY
        stqa    ZERO, vars+V_PKT
        br      have_packet
no_tiles:
        il      $66, 1
        stqa    $66, vars+V_EXH
        br      sched_next

# ---- the tile's last packets are starting: claim the next tile now, its putllc's
# status read when the tile is done (next_tile), by when the reservation's outcome has
# arrived instead of being waited for. Two packets ahead, not a tile, so that an SPE
# holds no more work than it is about to do and the SPEs still finish together.
        .set CLAIM_AHEAD_PACKET, 62
claim_ahead:
        lqa     $66, vars+V_EXH
        brnz    $66, have_packet              # no tile left anyway
        ila     $66, lockbuf
        lqa     $69, k_inc0
        lqa     $70, vars+V_EACNT
        TILE_CLAIM                            # its putllc's status not waited for
        stqa    $71, vars+V_AHEAD
        il      $66, 1
        stqa    $66, vars+V_PENDING
        br      have_packet

# ---- a new packet in the current context: the next of the tile, or of the next tile;
# its rays are generated next (modules/raygen.s)
packet_start:
        lqa     $66, vars+V_PKT
        ceqi    $67, $66, 64
        brnz    $67, new_tile                 # the tile is done
        ceqi    $67, $66, CLAIM_AHEAD_PACKET
        brnz    $67, claim_ahead
have_packet:
        lqa     $66, vars+V_PKT
        lqa     $67, vars+V_TILE
        stqa    $66, vars+V_CURPKT
        stqd    $66, CTX_PACKET(RAYS)         # where packet_done puts the results
        shli    $67, $67, 6
        stqd    $67, CTX_TILE64(RAYS)
        ai      $66, $66, 1
        stqa    $66, vars+V_PKT
