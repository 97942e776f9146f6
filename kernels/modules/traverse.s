# traverse.s — BVH traversal of a packet (paper section 4.1; Wald, Boulos, Shirley 2007).
#
# Traversal works on sibling pairs: one step takes an inner node the packet enters and
# tests both of its children at once, each with the first active ray's slab test and the
# packet's interval-arithmetic (IA) frustum test. The two children's tests are independent,
# so they fill each other's latencies. The BVH cache (modules/bvh_cache.s) keeps each pair
# axis-major:
#   +0  (min0.x, max0.x, min1.x, max1.x)   +16 the same for y   +32 for z
#   +48 (link0', meta0, link1', meta1)     link' = child-pair byte offset (inner) or
#                                          first triangle (leaf); meta = (count<<2|axis)<<4
# so a step needs no horizontal reductions: per axis, the planes are put in (near, far)
# order for the first ray (PERMk), and every slab test becomes "max over the axes of
# (entry, -exit)" with the exit negated in the odd lanes by the multipliers themselves.
# The multipliers carry a factor (1 -/+ 2^-16), and the offsets an absolute margin, that
# widen every box a little, so rounding can only make a box test say "hit", never drop a
# ray that reaches a triangle. The decision (descend to the near child and push the far
# one, take the one that is entered, or pop) is made with masks, without branches; only
# the third case (first ray misses a child the frustum does not rule out) branches, to
# find_first. A stack entry is a state: (link', meta, first active ray). A leaf goes to
# the triangle test (modules/triangle.s), which pops the next state when it is done.

        .text
# ---- one traversal step: test both children of CUR (an inner node the packet enters)
# $68/$70/$71: the pair's x/y/z planes, $73: (link', meta) of both children, $76: near
# child's table offset, $77: the entry a pop takes, $112: first-ray miss mask
# (lanes child 0, 0, 1, 1), $118: the children's first active rays.
        .align  3                             # pairs: even pipe at 8k, odd pipe at 8k+4
trav:
        and     $66, CUR, BMASK64   # the pair's cache line
        hbrr    .Lloop_br, trav
        nop
        rotqbyi $67, CUR, 4   # meta << 4
        rotmi   $72, $66, -2   # its tag's offset
        lqx     $68, BDATA, $66   # x planes (min0, max0, min1, max1)
        nop
        lqx     $70, BDATA16, $66   # y
        nop
        lqx     $71, BDATA32, $66   # z
        andi    $69, $67, 0x30   # split axis * 16
        lqd     $74, CTX_RAY_T(FT_ADDR)   # the first ray's t
        rotmi   $97, $67, -6   # triangle count: a leaf
        lqx     $73, BDATA48, $66   # (link', meta) of both children
        nop
        lqx     $75, BTAGS, $72
        nop
        lqx     $76, NEGTAB, $69   # all ones: child 1 is the near one
        nop
        lqd     $77, -16(STK)   # the entry a pop takes
        nop
        lqa     $78, k_pc0
        nop
        lqa     $79, k_pc1
        nop
        shufb   $95, CUR, CUR, PAT2   # this node's first active ray: changed?
        ceq     $115, $75, CUR   # the line holds this pair
        shufb   $80, $68, $68, PERMX   # planes in (near, far) order for the first ray
        nop
        shufb   $81, $70, $70, PERMY
        nop
        shufb   $82, $71, $71, PERMZ
        ceq     $95, $95, FIRST
        shufb   $83, $74, $74, FT_PAT   # (0, t, 0, t)
        fms     $84, $80, RX1, OR1X   # first ray: (entry, -exit) per child and axis
        lnop
        fms     $85, $81, RY1, OR1Y
        brz     $95, first_changed
        fms     $86, $82, RZ1, OR1Z
        brnz    $97, leaf
        xor     $83, $83, NEGODD   # (0, -t, 0, -t)
        lnop
        fma     $87, $80, PAX, OAX   # packet: both bounds, the smaller taken
        lnop
        fma     $88, $80, PBX, OBX
        lnop
        fma     $89, $81, PAY, OAY
        lnop
        fma     $90, $81, PBY, OBY
        lnop
        fma     $91, $82, PAZ, OAZ
        lnop
        fma     $92, $82, PBZ, OBZ
        lnop
        fcgt    $93, $84, $85
        lnop
        fcgt    $95, $86, $83
        lnop
        selb    $94, $85, $84, $93   # max(x, y)
        lnop
        selb    $96, $83, $86, $95   # max(z, t)
        lnop
        fcgt    $99, $87, $88
        lnop
        fcgt    $97, $94, $96
        lnop
        fcgt    $101, $89, $90
        lnop
        fcgt    $103, $91, $92
        lnop
        selb    $98, $96, $94, $97   # first ray: (entry, -exit) over the axes
        lnop
        selb    $100, $87, $88, $99
        lnop
        selb    $102, $89, $90, $101
        shufb   $111, $98, $98, SWAP
        selb    $104, $91, $92, $103
        lnop
        fcgt    $105, $100, $102
        lnop
        fcgt    $107, $104, F2
        lnop
        selb    $106, $102, $100, $105
        lnop
        selb    $108, F2, $104, $107
        lnop
        xor     $111, $111, SIGNS   # (exit, -entry)
        lnop
        fcgt    $109, $106, $108
        lnop
        fcgt    $112, $98, $111   # the first ray misses (lanes child 0, 0, 1, 1)
        lnop
        selb    $110, $108, $106, $109   # packet: (entry, -exit) over the axes
        lnop
        ai      S_STEPS, S_STEPS, 1
        shufb   $116, $112, $112, PAT0   # child 0 missed, every lane
        ceq     $93, STK, STKBASE
        shufb   $113, $110, $110, SWAP
        nop
        shufb   $117, $112, $112, PAT2   # child 1 missed
        or      $118, $116, $76
        lnop
        xor     $113, $113, SIGNS
        lnop
        andc    $118, $118, $117   # go to child 1
        lnop
        fcgt    $114, $110, $113   # the frustum misses
        lnop
        selb    $119, $78, $79, $118   # next state's pattern
        biz     $115, BMISSH
        selb    $120, $79, $78, $118   # pushed state's pattern
        lnop
        a       $124, $116, $117
        shufb   $122, $73, FIRST, $119
        andc    $125, $112, $114   # undecided: the first ray misses, the frustum not
        shufb   $123, $73, FIRST, $120
        shli    $124, $124, 4   # -32, -16, 0: stack delta - 16
        lnop
        and     $127, $112, $114   # early exits
        gb      $126, $125
        and     $121, $116, $117   # neither: pop
        lnop
        a       M1V, M1V, $112
        lnop
        a       EEV, EEV, $127
        lnop
        and     $93, $93, $121   # popping an empty stack: the packet is done
        brnz    $126, slow   # the third case: the only one that branches
        selb    CUR, $122, $77, $121
        lnop
        nop
        stqd    $123, 0(STK)   # stored either way; kept when both children go
        nop
        brnz    $93, packet_done
        a       STK, STK, $124
        lnop
        ai      STK, STK, 16
        lnop
        nop
.Lloop_br:
        br      trav

# a new state from a pop or a changed first ray: the step's own checks sort it out
        .set    .Lnewcur, trav

first_changed:
        shufb   FIRST, CUR, CUR, PAT2
        brsl    $0, set_first
        br      trav

# ---- the third case: the first ray misses a child the frustum does not rule out. Find the
# first ray from FIRST on that enters it; none means the child is skipped.
slow:
        ori     $126, FIRST, 0                # the children's first active rays
        brz     $125, .Lslow1
        shufb   $80, $68, $68, PAT0           # child 0: min, max planes
        shufb   $81, $68, $68, PAT1
        shufb   $82, $70, $70, PAT0
        shufb   $83, $70, $70, PAT1
        shufb   $84, $71, $71, PAT0
        shufb   $85, $71, $71, PAT1
        brsl    $0, find_first
        ceqi    $98, $97, -1
        brnz    $98, .Lslow1
        lqa     $98, k_child0
        andc    $112, $112, $98
        shufb   $99, $97, $97, PAT0
        lqa     $98, k_word0
        selb    $126, $126, $99, $98
.Lslow1:
        rotqbyi $90, $125, 8
        brz     $90, .Lslow_done
        shufb   $80, $68, $68, PAT2           # child 1
        shufb   $81, $68, $68, PAT3
        shufb   $82, $70, $70, PAT2
        shufb   $83, $70, $70, PAT3
        shufb   $84, $71, $71, PAT2
        shufb   $85, $71, $71, PAT3
        brsl    $0, find_first
        ceqi    $98, $97, -1
        brnz    $98, .Lslow_done
        lqa     $98, k_child1
        andc    $112, $112, $98
        shufb   $99, $97, $97, PAT0
        lqa     $98, k_word1
        selb    $126, $126, $99, $98
.Lslow_done:
        # the step's decision again, with the children's own first rays
        shufb   $116, $112, $112, PAT0
        shufb   $117, $112, $112, PAT2
        lqa     $78, k_pc0
        lqa     $79, k_pc1
        or      $118, $116, $76
        andc    $118, $118, $117
        selb    $119, $78, $79, $118
        selb    $120, $79, $78, $118
        and     $121, $116, $117
        shufb   $122, $73, $126, $119
        shufb   $123, $73, $126, $120
        a       $124, $116, $117
        shli    $124, $124, 4
        ceq     $93, STK, STKBASE
        and     $93, $93, $121
        selb    CUR, $122, $77, $121
        stqd    $123, 0(STK)
        brnz    $93, packet_done
        a       STK, STK, $124
        ai      STK, STK, 16
        br      .Lnewcur

# find_first: the first ray from FIRST on whose slab intervals with the box ($80/$81 min/max
# x, $82/$83 y, $84/$85 z planes, splats) overlap within [0, t], widened by 1 -/+ 2^-16;
# its index in $97, or -1. Uses $80..$111, $113..$124, $127.
find_first:
        fs      $80, $80, OXS
        fs      $81, $81, OXS
        fs      $82, $82, OYS
        fs      $83, $83, OYS
        fs      $84, $84, OZS
        fs      $85, $85, OZS
        rotmi   $86, FIRST, -3
        shli    $86, $86, 5                   # byte offset of the even vector at or below FIRST's
        rotmi   $117, $86, -2                 # its first ray
        lqa     $90, k_idx
        a       $117, $117, $90               # the ray indices of its lanes
        ai      $89, FIRST, -1
        lqa     $113, k_epslo
        lqa     $114, k_epshi
        ila     $88, CTX_RAY_RX
        a       $88, $88, RAYS
        # two vectors per pass (scheduled into even/odd pairs)
        .align  3
1:
        a       $90, $88, $86
        lnop
        cgt     $91, $117, $89
        lnop
        ai      $92, $117, 4
        lqd     $93, 0($90)
        ai      $86, $86, 32
        lqd     $94, 256($90)
        cgt     $95, $92, $89
        lqd     $96, 512($90)
        ai      $117, $117, 8
        lqd     $98, 16($90)
        ceqi    $104, $86, 256
        lqd     $99, 272($90)
        nop
        lqd     $100, 528($90)
        fm      $101, $80, $93
        lqd     $102, 768($90)
        fm      $105, $81, $93
        lqd     $106, 784($90)
        fm      $107, $82, $94
        lnop
        fm      $108, $83, $94
        lnop
        fm      $109, $84, $96
        lnop
        fm      $110, $85, $96
        lnop
        fm      $111, $80, $98
        lnop
        fm      $116, $81, $98
        lnop
        fm      $118, $82, $99
        lnop
        fm      $119, $83, $99
        lnop
        fm      $120, $84, $100
        lnop
        fm      $121, $85, $100
        lnop
        fcgt    $122, $101, $105
        lnop
        fcgt    $123, $107, $108
        lnop
        fcgt    $124, $109, $110
        lnop
        selb    $127, $101, $105, $122
        lnop
        selb    $87, $105, $101, $122
        lnop
        selb    $92, $107, $108, $123
        lnop
        selb    $93, $108, $107, $123
        lnop
        selb    $94, $109, $110, $124
        lnop
        selb    $96, $110, $109, $124
        lnop
        fcgt    $98, $127, $92
        lnop
        fcgt    $99, $94, ZERO
        lnop
        fcgt    $100, $87, $93
        lnop
        fcgt    $122, $96, $102
        lnop
        fcgt    $101, $111, $116
        lnop
        fcgt    $105, $118, $119
        lnop
        fcgt    $108, $120, $121
        lnop
        selb    $123, $92, $127, $98
        lnop
        selb    $107, ZERO, $94, $99
        lnop
        selb    $109, $87, $93, $100
        lnop
        selb    $124, $96, $102, $122
        lnop
        selb    $110, $111, $116, $101
        lnop
        selb    $98, $116, $111, $101
        lnop
        selb    $127, $118, $119, $105
        lnop
        selb    $92, $119, $118, $105
        lnop
        selb    $99, $120, $121, $108
        lnop
        selb    $94, $121, $120, $108
        lnop
        fcgt    $87, $123, $107
        lnop
        fcgt    $93, $109, $124
        lnop
        fcgt    $100, $110, $127
        lnop
        fcgt    $102, $99, ZERO
        lnop
        fcgt    $122, $98, $92
        lnop
        fcgt    $96, $94, $106
        lnop
        selb    $116, $107, $123, $87
        lnop
        selb    $111, $109, $124, $93
        lnop
        selb    $101, $127, $110, $100
        lnop
        selb    $119, ZERO, $99, $102
        lnop
        selb    $105, $98, $92, $122
        lnop
        selb    $118, $94, $106, $96
        lnop
        fm      $108, $116, $113
        lnop
        fm      $121, $111, $114
        lnop
        fcgt    $120, $101, $119
        lnop
        fcgt    $87, $105, $118
        lnop
        selb    $123, $119, $101, $120
        lnop
        selb    $107, $105, $118, $87
        lnop
        fm      $124, $123, $113
        lnop
        fm      $93, $107, $114
        lnop
        fcgt    $109, $108, $121
        lnop
        andc    $127, $91, $109
        lnop
        nop
        gb      $100, $127
        fcgt    $110, $124, $93
        lnop
        andc    $99, $95, $110
        lnop
        shli    $102, $100, 4
        lnop
        nop
        gb      $98, $99
        or      $103, $102, $98
        lnop
        nop
        brnz    $103, 2f
        nop
        brz     $104, 1b

        il      $97, -1
        bi      $0
2:      clz     $103, $103                    # 8 lanes: the first = clz - 24
        ai      $103, $103, -32               # (less the 8 rays $117 has moved on)
        a       $97, $117, $103
        bi      $0

# ---- set_first: the first ray's data from FIRST (splat)
set_first:
        rotmi   $100, FIRST, -2
        shli    $100, $100, 4                 # its vector's byte offset
        andi    $101, FIRST, 3
        shli    $101, $101, 4                 # its lane * 16
        ori     $102, RAYS, 0
        a       $102, $102, $100
        lqd     $103, CTX_RAY_RX($102)
        lqd     $104, CTX_RAY_RX+256($102)
        lqd     $105, CTX_RAY_RX+512($102)
        ila     $106, k_pat
        lqx     $107, $106, $101
        ila     $106, k_tpat
        lqx     FT_PAT, $106, $101
        ori     $106, RAYS, 0
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
        bi      $0
