# shade_cache.s — the shading module's first-call set-up and its caches' misses
# (modules/shade.s).
#
# The first call (shade_packet's prologue finds no "SHAD" flag in the area) fetches the
# shading block, splats the lights, clears the counters and every tag of the
# direct-mapped vertex and material caches (their sizes from the block), and says every
# light is visible, then goes back to .Lsh_ready. The misses: a material (.Lsh_mmiss, from
# the lighting's lookup: fetched and waited for, back to .Lsh_mhit), a vertex
# (sh_vertex_miss, from SH_VERTEX in the i-set's slow path: queued into a staging slot,
# landed by SH_LAND) and a triangle record the traversal's cache does not hold
# (sh_tri_miss, from SH_FETCH: queued, waited for before the records are read).
#
# sh_vertex_miss takes the area, the vertex, its tag's and line's addresses, the return,
# the lane's normal offset in the area and the vertex records' EA, and leaves its staging
# slot and the vertex in flight; sh_tri_miss the area, the record, where it goes and the
# return (tests/src/lib.rs's module harness checks both):
#
# Registers of sh_vertex_miss:
#   in:       $66 $81 $83 $84 $88 $89 $100 ZERO
#   out:      $82 $94
#   clobbers: $71..$77 $85..$87 $90 $125..$127
#
# Registers of sh_tri_miss:
#   in:       $66 $80 $82 $88 ZERO EATRIS
#   out:      -
#   clobbers: $81 $83 $84

        # ---- the first call: fetch the block, splat the lights, clear counters and caches
.Lsh_first:
        stqd    $68, SH_FLAG($66)
        SH_ADDI $72, $66, SH_BLOCK
        il      $73, SHADING_BLOCK_BYTES
        SH_GET  $72, $71, $73, $74
        SH_ADDI $71, $66, SH_DCOUNT
        stqd    ZERO, 0($71)                  # no vertex in flight
        il      $71, 10
        SH_FILL ZERO, SH_STATS
        ila     $90, sh_const
        lqd     $91, 64($90)
        lqd     $92, 80($90)
        lqd     $93, 96($90)
        lqd     $70, SH_BLOCK($66)
        rotqbyi $71, $70, SHB_LIGHT_COUNT
        SH_ADDI $72, $66, SH_BLOCK+SHB_LIGHTS
        SH_ADDI $73, $66, SH_LIGHTS
        brz     $71, 2f
1:      lqd     $74, 0($72)
        lqd     $75, 16($72)
        .irp    W, 74, 75                     # position, colour: x, y, z splats
        .irp    P, 91, 92, 93
        shufb   $76, $\W, $\W, $\P
        stqd    $76, (\W-74)*48+(\P-91)*16($73)
        .endr
        .endr
        ai      $72, $72, SHB_LIGHT_BYTES
        ai      $73, $73, SH_LIGHT_BYTES
        ai      $71, $71, -1
        brnz    $71, 1b
2:      il      $74, -1                       # every light visible (no shadow rays)
        il      $71, 8 * 16
        SH_FILL $74, SH_VIS
        lqd     $70, SH_BLOCK+SHB_MODE($66)   # mode, early, vertex log2, material log2
        il      $74, -1
        il      $75, 1
        rotqbyi $71, $70, 8
        shl     $71, $75, $71                 # vertex entries
        SH_FILL $74, SH_VTAGS
        rotqbyi $71, $70, 8
        shl     $71, $75, $71
        ai      $71, $71, -1
        shufb   $121, $71, $71, $91           # the vertex index mask in every lane
        stqd    $121, SH_VMASK($66)
        rotqbyi $71, $70, 12
        shl     $71, $75, $71                 # material entries
        SH_FILL $74, SH_MTAGS
        br      .Lsh_ready

.Lsh_mmiss:                                   # a material cache miss
        shli    $74, $110, 5
        a       $74, $74, $101
        il      $75, 32
        SH_GET  $73, $74, $75, $76
        stqd    $110, 0($72)
        SH_COUNT SHS_MMISS, $76
        br      .Lsh_mhit


# a vertex cache miss: vertex $81 into line $84, tag $83, its normal for $66 + $89; back
# to $88. The fetch is queued, not waited for, into a staging slot of its own; the tag
# becomes the vertex with bit 31 set (in flight) and the miss is counted. A copy is left
# to SH_LAND, which the slow path runs once the group's lanes are looked up: one
# wait for all their misses, then in lookup order each slot's normal (the one quadword
# of a vertex record the module reads) to its line (so a line ends up with the last
# vertex looked up there) and to the lane, and the vertex to the line's tag (landed). A
# lookup of a vertex in flight is no miss: its copy comes from its line, after the slot's
# (it leaves by the hinted return, which was 43% of the calls in the beetle).
# (Uses $71-$77, $82, $85-$87, $90, $94, $125-$127.)
sh_vertex_miss:
        .sched  pool=71-77,85-87,90,125-127 scratch=66-127
        hbr     .Lsh_vm_ret, $88
        ila     %o1, SH_DCOUNT
        a       %dc, $66, %o1
        lqd     %n, 0(%dc)                    # bytes of copies (32 each)
        lqd     %tag, 0($83)
        ilhu    %hb, 0x8000
        or      $94, $81, %hb                 # the vertex, in flight
        ceq     %inf, %tag, $94
        ila     %o2, SH_VSTAGE
        a       %sb, $66, %o2
        shli    %n2, %n, 1
        a       $82, %n2, %sb                 # its slot
        selb    %src, $82, $84, %inf          # in flight already: from its line
        a       %lane, $89, $66
        lqa     %plo, sh_const
        lqa     %pfh, sh_const+32
        lqa     %p1, sh_const+336
        shufb   %ll, %lane, %lane, %plo
        shufb   %tv, $83, $81, %plo
        shufb   %ltv, %ll, %tv, %pfh          # (-, the lane, the tag, the vertex), then
        shufb   %rec, %src, %ltv, %p1         # the source in front: one shuffle after it
        ila     %o3, SH_DEFER
        a       %db, $66, %o3
        a       %d2, %db, %n
        stqd    %rec, 0(%d2)
        stqd    $84, 16(%d2)                  # the line
        ai      %n1, %n, 32
        stqd    %n1, 0(%dc)
        brnz    %inf, .Lsh_vm_ret             # (the return hinted either way)
        .endsched
        .sched  pool=71-77,85-87,90,125-127 scratch=66-127
        lqd     %cnt, SH_STATS+SHS_VMISS($66)
        shli    %ea0, $81, 6
        a       %ea, %ea0, $100
        il      %size, 64
        il      %tg, SH_TAG
        il      %cmd, 0x40
        ai      %cnt1, %cnt, 1
        wrch    $MFC_LSA, $82
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, %ea
        wrch    $MFC_Size, %size
        wrch    $MFC_TagID, %tg
        wrch    $MFC_Cmd, %cmd
        stqd    $94, 0($83)                   # the tag: in flight
        stqd    %cnt1, SH_STATS+SHS_VMISS($66)
.Lsh_vm_ret:
        bi      $88
        .endsched

# a triangle record the traversal's cache does not hold: record $80 into $82, not waited
# for (SH_WAIT); back to $88
sh_tri_miss:
        hbr     1f, $88
        SH_COUNT SHS_TMISS, $84
        shli    $81, $80, 6
        a       $81, $81, EATRIS
        SH_QUEUE $82, $81, 64, $83
1:      bi      $88
