# refit.s — BVH refit on the SPEs (paper section 9.3; loader::spu_refit builds its work).
#
# Each frame of a moving scene the node bounds are recomputed bottom-up from the new
# vertices. The host lays the work out once per topology as items of REFIT_ITEM_BYTES in main
# memory: the nodes of one height (leaves are height 0, a parent is one above its highest
# child), up to REFIT_MAX_NODES of them, with a DMA list that gathers what they are folded
# from (a leaf's triangles' corners, 16 bytes from each vertex record; an inner node's child
# pair, one 64-byte line) and a DMA list that scatters the 32-byte node records back:
#
#   0   n_nodes, gather list bytes, hi offset (0: points, 16: boxes), EA of this height's
#       done counter
#   16  EA of the height below's done counter, its item count (0: none to wait for),
#       scatter list bytes, height
#   REFIT_ENTRIES  per node: elements to fold, node index, link, count_axis
#   REFIT_GATHER   gather list (8 bytes per element: size, EA)
#   REFIT_SCATTER  scatter list (8 bytes per node)
#
# Items are taken from a shared counter with an atomic getllar/putllc increment (as frame.s
# takes tiles). An item of height h starts gathering once every item of height h - 1 is
# done (their counter, polled with getllar, reached their count), which by induction means
# every lower height is. Double buffering: while an item is folded, the next item's block is
# fetched and, where its height's wait is already known to be over, its gather list runs.
#
# A fold starts from the first point or box and takes the new value per coordinate where
# fcgt says it is lower (minimum) or higher (maximum): loader::refit does the same, so the
# bounds are the host's bit for bit.
#
# Protocol: $3 = SPU index, $4 = EA of the 128-byte parameter block: items EA, item count,
# claim counter EA. At the end: refit_stats = items, nodes and polls (word 0 of three
# quadwords), outbound mailbox 1,
# stop 0x2000.

        .data
        .align 7
params:         .space 128
claimbuf:       .space 128
donebuf:        .space 128
pollbuf:        .space 128
item0:          .space REFIT_ITEM_BYTES
item1:          .space REFIT_ITEM_BYTES
data0:          .space REFIT_DATA_BYTES
data1:          .space REFIT_DATA_BYTES
out0:           .space REFIT_OUT_BYTES
out1:           .space REFIT_OUT_BYTES
        .global refit_stats
refit_stats:    .space 48
k_inc0:         .long 1, 0, 0, 0
k_w3:           .long 0, 0, 0, 0xffffffff

# registers: $2 zero; $10 item count, $11 items EA, $12 claim counter EA;
# current item: $20 block, $21 gathered data, $22 records out, $23 tag (0/1), $30 index;
# next item: $24, $25, $26, $27, $31; $32 the wait last seen over (EA of a done counter);
# $33 next item's gather issued early; $34 next item exists;
# statistics: $40 items, $41 nodes, $42 polls

        .text
        .global _start
_start:
        il      $2, 0
        ila     $5, params
        il      $6, 128
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $4
        wrch    $MFC_Size, $6
        wrch    $MFC_TagID, $2
        il      $7, 0x40                      # get
        wrch    $MFC_Cmd, $7
        il      $7, 1
        wrch    $MFC_WrTagMask, $7
        il      $7, 2
        wrch    $MFC_WrTagUpdate, $7
        rdch    $7, $MFC_RdTagStat
        lqd     $8, 0($5)
        ori     $11, $8, 0                    # items EA
        rotqbyi $10, $8, 4                    # item count
        rotqbyi $12, $8, 8                    # claim counter EA
        ila     $20, item0
        ila     $21, data0
        ila     $22, out0
        il      $23, 0
        ila     $24, item1
        ila     $25, data1
        ila     $26, out1
        il      $27, 1
        il      $32, -1
        il      $40, 0
        il      $41, 0
        il      $42, 0
        # the first item: its block, its height's wait, its gather
        brsl    $0, claim
        ori     $30, $3, 0
        clgt    $6, $10, $30
        brz     $6, finish
        ori     $4, $20, 0
        ori     $5, $23, 0
        brsl    $0, fetch_item
        ori     $5, $23, 0
        brsl    $0, wait_tag
        ori     $4, $20, 0
        brsl    $0, wait_level
        ori     $4, $20, 0
        ori     $5, $21, 0
        ori     $6, $23, 0
        brsl    $0, gather

item_loop:
        # claim the next item and fetch its block while the current one's gather runs
        brsl    $0, claim
        ori     $31, $3, 0
        il      $33, 0
        clgt    $34, $10, $31
        brz     $34, 1f
        ori     $4, $24, 0
        ori     $5, $27, 0
        brsl    $0, fetch_item
1:      ori     $5, $23, 0
        brsl    $0, wait_tag                  # the current item's corners or child pairs
        brz     $34, 2f
        ori     $5, $27, 0
        brsl    $0, wait_tag                  # the next item's block
        lqd     $6, 16($24)                   # its wait: counter EA, count
        rotqbyi $7, $6, 4
        ceq     $8, $6, $32
        ceqi    $9, $7, 0
        or      $8, $8, $9
        brz     $8, 2f                        # not known to be over: gather it later
        ori     $4, $24, 0
        ori     $5, $25, 0
        ori     $6, $27, 0
        brsl    $0, gather                    # gathers while the current item is folded
        il      $33, 1

        # fold the current item's nodes into their records
2:      lqd     $6, 0($20)                    # n_nodes, gather bytes, hi offset, done EA
        rotqbyi $15, $6, 8                    # offset of a box's maximum (0 for a point)
        ai      $16, $15, 16                  # element stride
        ori     $17, $6, 0                    # nodes left
        a       $41, $41, $6
        ai      $18, $20, REFIT_ENTRIES
        ori     $19, $21, 0
        ori     $28, $22, 0
        lqa     $29, k_w3
node_loop:
        lqd     $35, 0($18)                   # elements, node, link, count_axis
        lqd     $36, 0($19)                   # the first point or box
        lqx     $37, $19, $15
        a       $19, $19, $16
        ai      $38, $35, -1
        brz     $38, 4f
        hbrr    .Lfold_br, 3f
3:      lqd     $43, 0($19)
        lqx     $44, $19, $15
        a       $19, $19, $16
        ai      $38, $38, -1
        fcgt    $45, $36, $43
        fcgt    $46, $44, $37
        selb    $36, $36, $43, $45
        selb    $37, $37, $44, $46
.Lfold_br:
        brnz    $38, 3b
4:      rotqbyi $47, $35, 12                  # link into word 3
        selb    $36, $36, $47, $29            # min, link
        selb    $37, $37, $35, $29            # max, count_axis
        stqd    $36, 0($28)
        stqd    $37, 16($28)
        ai      $28, $28, 32
        ai      $18, $18, 16
        ai      $17, $17, -1
        brnz    $17, node_loop

        # scatter the records, and once they are out count the item done
        lqd     $7, 16($20)
        rotqbyi $7, $7, 8                     # scatter list bytes
        il      $8, REFIT_SCATTER
        a       $8, $8, $20
        ai      $9, $23, 2                    # tag 2 + buffer
        il      $5, 0x24                      # putl
        wrch    $MFC_LSA, $22
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $8
        wrch    $MFC_Size, $7
        wrch    $MFC_TagID, $9
        wrch    $MFC_Cmd, $5
        ori     $5, $9, 0
        brsl    $0, wait_tag
        lqd     $6, 0($20)
        rotqbyi $13, $6, 12                   # this height's done counter
        brsl    $0, count_done
        ai      $40, $40, 1
        brz     $34, finish
        brnz    $33, 5f
        ori     $4, $24, 0
        brsl    $0, wait_level
        ori     $4, $24, 0
        ori     $5, $25, 0
        ori     $6, $27, 0
        brsl    $0, gather
        # the next item becomes the current one
5:      ori     $30, $31, 0
        ori     $9, $20, 0
        ori     $20, $24, 0
        ori     $24, $9, 0
        ori     $9, $21, 0
        ori     $21, $25, 0
        ori     $25, $9, 0
        ori     $9, $22, 0
        ori     $22, $26, 0
        ori     $26, $9, 0
        ori     $9, $23, 0
        ori     $23, $27, 0
        ori     $27, $9, 0
        br      item_loop

finish:
        il      $5, 0xf                       # every tag: nothing left in flight
        wrch    $MFC_WrTagMask, $5
        il      $5, 2
        wrch    $MFC_WrTagUpdate, $5
        rdch    $5, $MFC_RdTagStat
        stqa    $40, refit_stats              # word 0 of each quadword
        stqa    $41, refit_stats+16
        stqa    $42, refit_stats+32
        il      $5, 1
        wrch    $SPU_WrOutMbox, $5
        stop    0x2000

# ---- claim: $3 = the next item's index (atomic fetch-and-increment of the claim counter)
claim:
        ila     $5, claimbuf
        lqa     $8, k_inc0
1:      wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $12
        il      $6, 0xd0                      # getllar
        wrch    $MFC_Cmd, $6
        rdch    $6, $MFC_RdAtomicStat
        lqd     $7, 0($5)
        a       $9, $7, $8
        stqd    $9, 0($5)
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $12
        il      $6, 0xb4                      # putllc
        wrch    $MFC_Cmd, $6
        rdch    $6, $MFC_RdAtomicStat
        andi    $6, $6, 1
        brnz    $6, 1b                        # reservation lost: again
        ori     $3, $7, 0
        bi      $0

# ---- count_done: atomic increment of the done counter at EA $13 (a quadword's word 0)
count_done:
        ila     $5, donebuf
        lqa     $8, k_inc0
        andi    $4, $13, 127                  # its offset in the line
        andi    $9, $13, -128
1:      wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $9
        il      $6, 0xd0                      # getllar
        wrch    $MFC_Cmd, $6
        rdch    $6, $MFC_RdAtomicStat
        lqx     $7, $5, $4
        a       $7, $7, $8
        stqx    $7, $5, $4
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $9
        il      $6, 0xb4                      # putllc
        wrch    $MFC_Cmd, $6
        rdch    $6, $MFC_RdAtomicStat
        andi    $6, $6, 1
        brnz    $6, 1b
        bi      $0

# ---- fetch_item: the block of item $3 into local store at $4, tag $5
fetch_item:
        shli    $6, $3, REFIT_ITEM_SHIFT
        a       $6, $6, $11
        il      $7, REFIT_ITEM_BYTES
        il      $8, 0x40                      # get
        wrch    $MFC_LSA, $4
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $6
        wrch    $MFC_Size, $7
        wrch    $MFC_TagID, $5
        wrch    $MFC_Cmd, $8
        bi      $0

# ---- wait_tag: until the DMA of tag $5 is done
wait_tag:
        il      $6, 1
        shl     $6, $6, $5
        wrch    $MFC_WrTagMask, $6
        il      $6, 2
        wrch    $MFC_WrTagUpdate, $6
        rdch    $6, $MFC_RdTagStat
        bi      $0

# ---- wait_level: until the height below item block $4's is done (its done counter
# reached its item count), polling the counter with getllar; $32 remembers the last wait
# seen over
wait_level:
        lqd     $6, 16($4)
        rotqbyi $7, $6, 4                     # items to wait for
        brz     $7, 2f
        ceq     $8, $6, $32
        brnz    $8, 2f
        ila     $5, pollbuf
        andi    $4, $6, 127
        andi    $9, $6, -128
1:      wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $9
        il      $8, 0xd0                      # getllar
        wrch    $MFC_Cmd, $8
        rdch    $8, $MFC_RdAtomicStat
        lqx     $8, $5, $4
        ai      $42, $42, 1
        clgt    $8, $7, $8
        brnz    $8, 1b
        ori     $32, $6, 0
2:      bi      $0

# ---- gather: item block $4's gather list into local store at $5, tag $6
gather:
        lqd     $7, 0($4)
        rotqbyi $7, $7, 4                     # list bytes
        il      $8, REFIT_GATHER
        a       $8, $8, $4
        il      $9, 0x44                      # getl
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $8
        wrch    $MFC_Size, $7
        wrch    $MFC_TagID, $6
        wrch    $MFC_Cmd, $9
        bi      $0
