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
# FIND_FIRST. A stack entry is a state: (link', meta, first active ray). A leaf goes to
# the triangle test (modules/triangle.s), which pops the next state when it is done.
#
# Across the modules: a step whose pair is not in the BVH cache branches to BMISSH (the
# handler modules/frame.s chose, in modules/bvh_cache.s) with $66 = CUR & BMASK64 (the
# line's offset in BDATA) and $72 = $66 / 4 (its tag's offset in BTAGS), which the
# handler takes as they are (its `# Registers` block); the handler comes back to `trav`.

        .text
# ---- one traversal step: test both children of CUR (an inner node the packet enters)
# $68/$70/$71: the pair's x/y/z planes, $73: (link', meta) of both children, $76: near
# child's table offset, $77: the entry a pop takes, $112: first-ray miss mask
# (lanes child 0, 0, 1, 1), $118: the children's first active rays.
        .ifdef  EXT_MULTIHINT
# With several hint entries (docs/extensions.md, Multihint) the step's three early exits
# (first_changed, leaf, the BVH cache's miss) are one `bi` to a target chosen with selb
# from conditions known 12 cycles into the step, hinted at once and taken after the first
# ray's and the frustum's tests (the common case: its own next instruction). Its hint
# keeps an entry of its own beside the loop's, so no exit is mispredicted either way.
        .sched  scratch=66-127
trav:
      ! hbrr    .Lloop_br, trav
        and     $66, CUR, BMASK64             # the pair's cache line
        shufb   $67, CUR, CUR, PAT1           # meta << 4, every lane
        rotmi   $72, $66, -2                  # its tag's offset
        lqx     $68, BDATA, $66               # x planes (min0, max0, min1, max1)
        lqx     $70, BDATA16, $66             # y
        lqx     $71, BDATA32, $66             # z
        lqx     $73, BDATA48, $66             # (link', meta) of both children
        lqx     $75, BTAGS, $72
        andi    $69, $67, 0x30                # split axis * 16
        lqx     $76, NEGTAB, $69              # all ones: child 1 is the near one
        lqd     $74, CTX_RAY_T(FT_ADDR)               # the first ray's t
        lqd     $77, -16(STK)                 # the entry a pop takes
        lqa     $78, k_pc0
        lqa     $79, k_pc1
        shufb   $80, $68, $68, PERMX          # planes in (near, far) order for the first ray
        shufb   $81, $70, $70, PERMY
        shufb   $82, $71, $71, PERMZ
        shufb   $83, $74, $74, FT_PAT         # (0, t, 0, t)
        xor     $83, $83, NEGODD              # (0, -t, 0, -t)
        fms     $84, $80, RX1, OR1X           # first ray: (entry, -exit) per child and axis
        fms     $85, $81, RY1, OR1Y
        fms     $86, $82, RZ1, OR1Z
        fma     $87, $80, PAX, OAX            # packet: both bounds, the smaller taken
        fma     $88, $80, PBX, OBX
        fma     $89, $81, PAY, OAY
        fma     $90, $81, PBY, OBY
        fma     $91, $82, PAZ, OAZ
        fma     $92, $82, PBZ, OBZ
        shufb   $116, CUR, CUR, PAT2          # this node's first active ray: unchanged?
        ceq     $116, $116, FIRST
        rotmi   $117, $67, -6                 # triangle count: 0 for an inner node
        ceqi    $117, $117, 0
        and     $118, $116, $117              # a step (the lookup decides the rest)
        lqa     $119, k_trav_to                 # (first_changed, leaf, .Ltrav_on, -)
        rotqbyi $120, $119, 4
        rotqbyi $121, $119, 8
        selb    $122, $119, $120, $116        # first ray changed, else a leaf
        ceq     $115, $75, CUR                # the line holds this pair
        selb    $123, BMISSH, $121, $115      # a step: on, or the miss handler
        selb    $124, $122, $123, $118        # where the step goes
        sf      S_STEPS, $118, S_STEPS        # +1 for a step
        hbr     .Ltop_br, $124                # (the first ray's tests take the 11 cycles:
        fcgt    $93, $84, $85 @after $124     # they wait for the target, which goes first)
        selb    $94, $85, $84, $93            # max(x, y)
        fcgt    $95, $86, $83
        selb    $96, $83, $86, $95            # max(z, t)
        fcgt    $97, $94, $96
        selb    $98, $96, $94, $97            # first ray: (entry, -exit) over the axes
        fcgt    $99, $87, $88 @after $124
        selb    $100, $87, $88, $99
        fcgt    $101, $89, $90 @after $124
        selb    $102, $89, $90, $101
        fcgt    $103, $91, $92 @after $124
        selb    $104, $91, $92, $103
        fcgt    $105, $100, $102
        selb    $106, $102, $100, $105
        fcgt    $107, $104, F2
        selb    $108, F2, $104, $107
        fcgt    $109, $106, $108
        selb    $110, $108, $106, $109        # packet: (entry, -exit) over the axes
        shufb   $111, $98, $98, SWAP
        xor     $111, $111, SIGNS             # (exit, -entry)
        fcgt    $112, $98, $111               # the first ray misses (lanes child 0, 0, 1, 1)
        shufb   $113, $110, $110, SWAP
        xor     $113, $113, SIGNS
        fcgt    $114, $110, $113              # the frustum misses
.Ltop_br:
      ! bi      $124
        .endsched
        .sched  scratch=66-127
.Ltrav_on:
        shufb   $116, $112, $112, PAT0        # child 0 missed, every lane
        shufb   $117, $112, $112, PAT2        # child 1 missed
        or      $118, $116, $76
        andc    $118, $118, $117              # go to child 1
        selb    $119, $78, $79, $118          # next state's pattern
        selb    $120, $79, $78, $118          # pushed state's pattern
        and     $121, $116, $117              # neither: pop
        shufb   $122, $73, FIRST, $119
        shufb   $123, $73, FIRST, $120
        a       $124, $116, $117
        shli    $124, $124, 4                 # -32, -16, 0: stack delta - 16
        ai      $124, $124, 16                # (the delta, one add on the stack's path)
        andc    $125, $112, $114              # undecided: the first ray misses, the frustum not
        gb      $126, $125
        a       M1V, M1V, $112
        and     $127, $112, $114              # early exits
        a       EEV, EEV, $127
      ! brnz    $126, slow                    # the third case
        ceq     $93, STK, STKBASE
        and     $93, $93, $121                # popping an empty stack: the packet is done
        selb    CUR, $122, $77, $121
      ! stqd    $123, 0(STK)                  # stored either way; kept when both children go
      ! brnz    $93, packet_done
        a       STK, STK, $124
.Lloop_br:
      ! br      trav
        .endsched
        .else
        .sched  scratch=66-127
trav:
      ! hbrr    .Lloop_br, trav
        and     $66, CUR, BMASK64             # the pair's cache line
        rotqbyi $67, CUR, 4                   # meta << 4
        rotmi   $72, $66, -2                  # its tag's offset
        lqx     $68, BDATA, $66               # x planes (min0, max0, min1, max1)
        lqx     $70, BDATA16, $66             # y
        lqx     $71, BDATA32, $66             # z
        lqx     $73, BDATA48, $66             # (link', meta) of both children
        lqx     $75, BTAGS, $72
        andi    $69, $67, 0x30                # split axis * 16
        lqx     $76, NEGTAB, $69              # all ones: child 1 is the near one
        lqd     $74, CTX_RAY_T(FT_ADDR)               # the first ray's t
        lqd     $77, -16(STK)                 # the entry a pop takes
        lqa     $78, k_pc0
        lqa     $79, k_pc1
        shufb   $95, CUR, CUR, PAT2           # this node's first active ray: changed?
        ceq     $95, $95, FIRST
        rotmi   $97, $67, -6                  # triangle count: a leaf
      ! brz     $95, first_changed
      ! brnz    $97, leaf
        ai      S_STEPS, S_STEPS, 1
        shufb   $80, $68, $68, PERMX          # planes in (near, far) order for the first ray
        shufb   $81, $70, $70, PERMY
        shufb   $82, $71, $71, PERMZ
        shufb   $83, $74, $74, FT_PAT         # (0, t, 0, t)
        xor     $83, $83, NEGODD              # (0, -t, 0, -t)
        fms     $84, $80, RX1, OR1X           # first ray: (entry, -exit) per child and axis
        fms     $85, $81, RY1, OR1Y
        fms     $86, $82, RZ1, OR1Z
        fma     $87, $80, PAX, OAX            # packet: both bounds, the smaller taken
        fma     $88, $80, PBX, OBX
        fma     $89, $81, PAY, OAY
        fma     $90, $81, PBY, OBY
        fma     $91, $82, PAZ, OAZ
        fma     $92, $82, PBZ, OBZ
        fcgt    $93, $84, $85
        selb    $94, $85, $84, $93            # max(x, y)
        fcgt    $95, $86, $83
        selb    $96, $83, $86, $95            # max(z, t)
        fcgt    $97, $94, $96
        selb    $98, $96, $94, $97            # first ray: (entry, -exit) over the axes
        fcgt    $99, $87, $88
        selb    $100, $87, $88, $99
        fcgt    $101, $89, $90
        selb    $102, $89, $90, $101
        fcgt    $103, $91, $92
        selb    $104, $91, $92, $103
        fcgt    $105, $100, $102
        selb    $106, $102, $100, $105
        fcgt    $107, $104, F2
        selb    $108, F2, $104, $107
        fcgt    $109, $106, $108
        selb    $110, $108, $106, $109        # packet: (entry, -exit) over the axes
        shufb   $111, $98, $98, SWAP
        xor     $111, $111, SIGNS             # (exit, -entry)
        fcgt    $112, $98, $111               # the first ray misses (lanes child 0, 0, 1, 1)
        shufb   $113, $110, $110, SWAP
        xor     $113, $113, SIGNS
        fcgt    $114, $110, $113              # the frustum misses
        ceq     $115, $75, CUR                # the line holds this pair
      ! biz     $115, BMISSH
        shufb   $116, $112, $112, PAT0        # child 0 missed, every lane
        shufb   $117, $112, $112, PAT2        # child 1 missed
        or      $118, $116, $76
        andc    $118, $118, $117              # go to child 1
        selb    $119, $78, $79, $118          # next state's pattern
        selb    $120, $79, $78, $118          # pushed state's pattern
        and     $121, $116, $117              # neither: pop
        shufb   $122, $73, FIRST, $119
        shufb   $123, $73, FIRST, $120
        a       $124, $116, $117
        shli    $124, $124, 4                 # -32, -16, 0: stack delta - 16
        andc    $125, $112, $114              # undecided: the first ray misses, the frustum not
        gb      $126, $125
        a       M1V, M1V, $112
        and     $127, $112, $114              # early exits
        a       EEV, EEV, $127
      ! brnz    $126, slow                    # the third case: the only one that branches
        ceq     $93, STK, STKBASE
        and     $93, $93, $121                # popping an empty stack: the packet is done
        selb    CUR, $122, $77, $121
      ! stqd    $123, 0(STK)                  # stored either way; kept when both children go
      ! brnz    $93, packet_done
        a       STK, STK, $124
        ai      STK, STK, 16
.Lloop_br:
      ! br      trav
        .endsched
        .endif

# a search's start: the box's planes relative to the packet's origin, the even vector at
# or below FIRST ($86 its byte offset, $117 its lanes' ray indices), the rounding margins
# ($113, $114) and the ray directions' base ($88)
        .macro  FF_START
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
        .endm

# a pass's two vectors of rays: directions and t
        .macro  FF_PASS_LOADS
        a       $90, $88, $86
        lqd     %rx0, 0($90)
        lqd     %ry0, 256($90)
        lqd     %rz0, 512($90)
        lqd     %t0, 768($90)
        lqd     %rx1, 16($90)
        lqd     %ry1, 272($90)
        lqd     %rz1, 528($90)
        lqd     %t1, 784($90)
        .endm

# one vector V of 4 rays against the child's box: the entry (largest near plane, at least 0)
# and exit (smallest far plane, at most t) distances from the sorted plane distances, widened
# by the rounding margins ($113, $114); %miss\V set where the ray misses the box
        .macro  SLAB_MISS V
        fcgt    %m1\V, %lx\V, %ly\V
        selb    %e1\V, %ly\V, %lx\V, %m1\V
        fcgt    %m2\V, %lz\V, ZERO
        selb    %e2\V, ZERO, %lz\V, %m2\V
        fcgt    %m3\V, %e1\V, %e2\V
        selb    %en\V, %e2\V, %e1\V, %m3\V
        fcgt    %m4\V, %hx\V, %hy\V
        selb    %x1\V, %hx\V, %hy\V, %m4\V
        fcgt    %m5\V, %hz\V, %t\V
        selb    %x2\V, %hz\V, %t\V, %m5\V
        fcgt    %m6\V, %x1\V, %x2\V
        selb    %ex\V, %x1\V, %x2\V, %m6\V
        fm      %enw\V, %en\V, $113
        fm      %exw\V, %ex\V, $114
        fcgt    %miss\V, %enw\V, %exw\V
        .endm

# the first of the pass's 8 rays (two vectors) that are active and enter the box, as a
# bit mask in $103 (0: none), the pass moved on by 8 rays, $104 set when the packet is done
        .macro  FF_FIRST_HIT
        ai      %idx1, $117, 4
        cgt     %act0, $117, $89
        cgt     %act1, %idx1, $89
        andc    %hit0, %act0, %miss0
        andc    %hit1, %act1, %miss1
        gb      %g0, %hit0
        gb      %g1, %hit1
        shli    %g0s, %g0, 4
        or      $103, %g0s, %g1
        ai      $86, $86, 32
        ai      $117, $117, 8
        ceqi    $104, $86, 256
        .endm

# FIND_FIRST: the first ray from FIRST on whose slab intervals with the box ($80/$81 min/max
# x, $82/$83 y, $84/$85 z planes, splats) overlap within [0, t], widened by 1 -/+ 2^-16;
# its index in $97, or -1. Uses $80..$111, $113..$124, $127. Inline in `slow`, twice: a
# call and its return were two more branches to mispredict per search.
        .macro  FIND_FIRST
        FF_START
        .ifdef  EXT_MULTIHINT
        hbrr    .Lff_none\@, 3f               # the search's exit when no ray enters, hinted
        .endif                                # ahead: the loop's hint keeps its own entry
        # two vectors per pass (scheduled into even/odd pairs)
        .sched  pool=91-96,98-102,105-111,116,118-124,127,87 scratch=66-127
1:
        FF_PASS_LOADS
        .irp    V, 0, 1
        fm      %ax\V, $80, %rx\V
        fm      %bx\V, $81, %rx\V
        fm      %ay\V, $82, %ry\V
        fm      %by\V, $83, %ry\V
        fm      %az\V, $84, %rz\V
        fm      %bz\V, $85, %rz\V
        fcgt    %mx\V, %ax\V, %bx\V
        fcgt    %my\V, %ay\V, %by\V
        fcgt    %mz\V, %az\V, %bz\V
        selb    %lx\V, %ax\V, %bx\V, %mx\V
        selb    %hx\V, %bx\V, %ax\V, %mx\V
        selb    %ly\V, %ay\V, %by\V, %my\V
        selb    %hy\V, %by\V, %ay\V, %my\V
        selb    %lz\V, %az\V, %bz\V, %mz\V
        selb    %hz\V, %bz\V, %az\V, %mz\V
        SLAB_MISS \V
        .endr
        FF_FIRST_HIT
        hbrr    .Lff_br\@, 1b                 # (most searches take a few passes)
      ! brnz    $103, 2f
.Lff_br\@:
      ! brz     $104, 1b
        .endsched
        il      $97, -1
.Lff_none\@:
        br      3f
2:      clz     $103, $103                    # 8 lanes: the first = clz - 24
        ai      $103, $103, -32               # (less the 8 rays $117 has moved on)
        a       $97, $117, $103
3:
        .endm

# FIND_FIRST for a packet whose rays point one way on every axis (the multihint variant
# only, though it needs no extension): the planes put in (smaller, larger) distance order
# once per search by the first ray's signs (NEGTAB) instead of per ray and axis (9 even-pipe
# instructions fewer per vector of 4 rays); exact, since (min - o) * r <= (max - o) * r for
# every ray r of the sign the packet's corner rays share.
        .ifdef  EXT_MULTIHINT
        .macro  FIND_FIRST_SIGNED
        lqd     $91, 0(NEGTAB)                # the packet's rays all point the first ray's
        lqd     $92, 16(NEGTAB)               # way on every axis: the smaller of a slab's
        lqd     $93, 32(NEGTAB)               # two distances is its min plane's when positive
        selb    $94, $80, $81, $91
        selb    $81, $81, $80, $91
        ori     $80, $94, 0
        selb    $94, $82, $83, $92
        selb    $83, $83, $82, $92
        ori     $82, $94, 0
        selb    $94, $84, $85, $93
        selb    $85, $85, $84, $93
        ori     $84, $94, 0
        FF_START
        hbrr    .Lff_none\@, 3f               # the search's exit when no ray enters, hinted
        # two vectors per pass (scheduled into even/odd pairs)
        .sched  pool=91-96,98-102,105-111,116,118-124,127,87 scratch=66-127
1:
        FF_PASS_LOADS
        .irp    V, 0, 1
        fm      %lx\V, $80, %rx\V
        fm      %hx\V, $81, %rx\V
        fm      %ly\V, $82, %ry\V
        fm      %hy\V, $83, %ry\V
        fm      %lz\V, $84, %rz\V
        fm      %hz\V, $85, %rz\V
        SLAB_MISS \V
        .endr
        FF_FIRST_HIT
        hbrr    .Lff_br\@, 1b                 # (most searches take a few passes)
      ! brnz    $103, 2f
.Lff_br\@:
      ! brz     $104, 1b
        .endsched
        il      $97, -1
.Lff_none\@:
        br      3f
2:      clz     $103, $103                    # 8 lanes: the first = clz - 24
        ai      $103, $103, -32               # (less the 8 rays $117 has moved on)
        a       $97, $117, $103
3:
        .endm
        .endif

# a new state from a pop or a changed first ray: the step's own checks sort it out
        .set    .Lnewcur, trav

        .ifdef  EXT_MULTIHINT
        .sched  scratch=66-127                # (multihint: scheduled, which needs no extension)
first_changed:
        hbrr    .Lfc_br, trav
        shufb   FIRST, CUR, CUR, PAT2
        SET_FIRST
.Lfc_br:
      ! br      trav
        .endsched
        .else
first_changed:
        hbrr    .Lfc_br, trav                 # (set_first inline: no call and return
        shufb   FIRST, CUR, CUR, PAT2         # to mispredict, and the way back hinted)
        SET_FIRST
.Lfc_br:
        br      trav
        .endif

# one child of the third case: its min and max planes (patterns LO, HI), its first ray
# (FIND_FIRST); none: on to SKIP; else the child is no longer missed (MISS: its lanes of
# $112) and its first ray goes to its word (WORD) of $126
        .macro  SLOW_CHILD lo, hi, skip, miss, word
        shufb   $80, $68, $68, \lo
        shufb   $81, $68, $68, \hi
        shufb   $82, $70, $70, \lo
        shufb   $83, $70, $70, \hi
        shufb   $84, $71, $71, \lo
        shufb   $85, $71, $71, \hi
        FIND_FIRST
        ceqi    $98, $97, -1
        brnz    $98, \skip
        lqa     $98, \miss
        andc    $112, $112, $98
        shufb   $99, $97, $97, PAT0
        lqa     $98, \word
        selb    $126, $126, $99, $98
        .endm

# ---- the third case: the first ray misses a child the frustum does not rule out. Find the
# first ray from FIRST on that enters it; none means the child is skipped.
        .ifdef  EXT_MULTIHINT
# (multihint) one search code for either child: the first search takes child 0 if it is
# undecided, else child 1; whether a second one (child 1) follows is known on entry, so
# its branch is a hinted `bi` and the way back to the search a hinted `br`, in entries of
# their own beside the search loop's; a search that finds no ray changes nothing (masks,
# no branch). $66/$67 the child's (min, max) patterns, $72 its lanes of $112, $74 its
# word of $126, $75 where the search goes when it is done.
        .macro  SLOW_SEARCH find
        shufb   $80, $68, $68, $66
        shufb   $81, $68, $68, $67
        shufb   $82, $70, $70, $66
        shufb   $83, $70, $70, $67
        shufb   $84, $71, $71, $66
        shufb   $85, $71, $71, $67
        \find
        ceqi    $98, $97, -1                  # none: the child is skipped
        andc    $99, $72, $98
        andc    $112, $112, $99               # else no longer missed
        shufb   $100, $97, $97, PAT0
        andc    $98, $74, $98
        selb    $126, $126, $100, $98         # and its first ray goes to its word
        .endm
slow:
        ori     $126, FIRST, 0                # the children's first active rays
        shufb   $90, $125, $125, PAT0         # child 0 undecided, every lane
        shufb   $91, $125, $125, PAT2         # child 1 undecided
        and     $92, $90, $91                 # both: a second search
        ila     $93, .Lslow_again
        ila     $94, .Lslow_done
        selb    $75, $94, $93, $92
        hbr     .Lslow_more_br, $75
        selb    $66, PAT2, PAT0, $90          # the first search's child
        selb    $67, PAT3, PAT1, $90
        lqa     $93, k_child0
        lqa     $94, k_child1
        selb    $72, $94, $93, $90
        lqa     $93, k_word0
        lqa     $94, k_word1
        selb    $74, $94, $93, $90
        ceq     $98, PAX, ZERO                # an axis the packet's rays cross both ways
        ceq     $99, PAY, ZERO                # (raygen.s: PA is 0 there): the search for
        ceq     $100, PAZ, ZERO               # any signs, else the signed one
        or      $98, $98, $99
        or      $98, $98, $100
        ila     $93, .Lslow_search
        ila     $94, .Lslow_search_any
        selb    $78, $93, $94, $98
        hbr     .Lslow_back_br, $78
        brnz    $98, .Lslow_search_any
.Lslow_search:
        SLOW_SEARCH FIND_FIRST_SIGNED
.Lslow_more_br:
        bi      $75
.Lslow_again:                                 # the second search: child 1
        hbrr    .Lslow_more_br, .Lslow_done
        ori     $66, PAT2, 0
        ori     $67, PAT3, 0
        lqa     $72, k_child1
        lqa     $74, k_word1
        ila     $75, .Lslow_done
.Lslow_back_br:
        bi      $78
.Lslow_search_any:                            # (rare: its way on is not hinted)
        SLOW_SEARCH FIND_FIRST
        bi      $75
        .else
slow:
        ori     $126, FIRST, 0                # the children's first active rays
        brz     $125, .Lslow1
        SLOW_CHILD PAT0, PAT1, .Lslow1, k_child0, k_word0
.Lslow1:
        rotqbyi $90, $125, 8
        brz     $90, .Lslow_done
        SLOW_CHILD PAT2, PAT3, .Lslow_done, k_child1, k_word1
        .endif
.Lslow_done:
        # the step's decision again, with the children's own first rays
        hbrr    .Lslow_br, .Lnewcur
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
.Lslow_br:
        br      .Lnewcur


# ---- set_first: the first ray's data from FIRST (splat), as a call (SET_FIRST, regs.inc)
set_first:
        SET_FIRST
        bi      $0
