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
lqd     $74, 0(FT_ADDR)               # the first ray's t
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
! brz     $115, bvh_miss
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
! br      trav
