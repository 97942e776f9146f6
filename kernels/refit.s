# refit.s — BVH refit on the SPEs (paper section 9.3; loader::spu_refit builds its work).
#
# Each frame of a moving scene the node bounds are recomputed bottom-up from the new
# vertices. The host lays the work out once per topology as items in main memory
# (loader::spu_refit::RefitPlan): height 0 are whole subtrees (a root and its descendants,
# which pre-order pair allocation keeps in one node range), each folded in local store from
# its distinct vertices, gathered once by a DMA list (16 bytes of each vertex record), its
# inner nodes from the records just folded, and written back by one put of the range; the
# nodes above them (the upper tree) come in items of one height, up to REFIT_MAX_NODES, each
# node's child pair gathered from main memory (one 64-byte line) and its record scattered
# back by a DMA list. An index of quadwords (block EA, block bytes) finds the blocks; a
# block is
#
#   0   n_nodes, gather list bytes, child pairs in local store (1: folded here, 0:
#       gathered), EA of this height's row of done counters
#   16  EA of the height below's row, its item count (0: none to wait for), scatter list
#       bytes, height
#   32  offset of the gather list, offset of the scatter list, leaves, -
#   48  per node, the leaves first: corners | (record offset << 16), source (a leaf: the
#       block offset of its corners' offsets into the gathered vertices, a halfword each; an
#       inner node: its child pair's offset), link, count_axis
#
# Work sharing: SPE i starts with items [i*C, (i+1)*C) handed out in the parameters, then
# takes ranges from a shared counter with an atomic getllar/putllc (as frame.s takes tiles):
# (tail - v) >> shift items (at least one) while below `tail`, and everything from `tail`
# on (the top heights, one item each, so that one SPE refits the top of the tree without
# waiting for other SPEs' counters). A putllc is settled at a quantum boundary, so claims
# are few and large first, small at the end (guided self-scheduling).
#
# Heights in order: an item of height h starts gathering once the items of height h - 1 are
# done; each SPE counts its finished items per height in its own quadword of the height's
# row (done row + 16 * SPE index, written with a plain put: no lock), and a waiting SPE
# sums the row. By induction every lower height is then done too.
#
# Double buffering: while an item is folded, the next item's block is fetched and, where
# its height's wait is already known to be over, its gather list runs.
#
# A fold starts from the first point or box and takes the new value per coordinate where
# fcgt says it is lower (minimum) or higher (maximum): loader::refit does the same, so the
# bounds are the host's bit for bit.
#
# The loops: a leaf's corners a triangle a turn (three halfword offsets, three loads,
# three folds),
# then the inner nodes; branches hinted, so that the only mispredicted branch is the end of
# a leaf's triangles.
#
# Protocol: $3 = SPU index, $4 = EA of the 128-byte parameter block: (index EA, item count,
# claim counter EA, tail), (shift, first range per SPE, -, -). At the end: refit_stats =
# items, nodes and polls (word 0 of three quadwords), outbound mailbox 1, stop 0x2000.

        .data
        .align 7
params:         .space 128
claimbuf:       .space 128
donebuf:        .space 128
pollbuf:        .space 256
idxbuf:         .space 128
item0:          .space REFIT_ITEM_BYTES
item1:          .space REFIT_ITEM_BYTES
data0:          .space REFIT_DATA_BYTES
data1:          .space REFIT_DATA_BYTES
out0:           .space REFIT_OUT_BYTES
out1:           .space REFIT_OUT_BYTES
        .global refit_stats
refit_stats:    .space 48
k_w3:           .long 0, 0, 0, 0xffffffff
k_lo16:         .long 0xffff, 0, 0, 0

# registers: $2 zero; $10 item count, $11 index EA, $12 claim counter EA, $13 tail,
# $14 claim shift, $15 this SPE's offset in a done row (16 * index);
# current item: $20 block, $21 gathered data, $22 records out, $23 tag (0/1), $30 index;
# next item: $24, $25, $26, $27, $31; $51 end of the claimed range;
# $32 the wait last seen over (EA of a done row); $33 next item's gather issued early;
# $34 next item exists; $49 height counted in $50 (items this SPE finished of it);
# statistics: $40 items, $41 nodes, $42 polls

        .text
        .global _start
_start:
        il      $2, 0
        shli    $15, $3, 4
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
        ori     $11, $8, 0                    # index EA
        rotqbyi $10, $8, 4                    # item count
        rotqbyi $12, $8, 8                    # claim counter EA
        rotqbyi $13, $8, 12                   # tail
        lqd     $8, 16($5)
        ori     $14, $8, 0                    # shift
        rotqbyi $9, $8, 4                     # first range: [index * C, index * C + C)
        mpyu    $30, $3, $9
        a       $51, $30, $9
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
        il      $49, -1
        il      $50, 0
        brnz    $9, 1f
        brsl    $0, claim                     # no first range: claim one
        ori     $30, $3, 0
        ori     $51, $4, 0
1:      clgt    $6, $10, $30
        brz     $6, finish
        # the first item: its block, its height's wait, its gather
        ori     $3, $30, 0
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
        # the next item: the next of the range, or the first of a new one; its block is
        # fetched while the current one's gather runs
        ai      $31, $30, 1
        clgt    $6, $51, $31
        brnz    $6, 1f
        brsl    $0, claim
        ori     $31, $3, 0
        ori     $51, $4, 0
1:      il      $33, 0
        clgt    $34, $10, $31
        brz     $34, 1f
        ori     $3, $31, 0
        ori     $4, $24, 0
        ori     $5, $27, 0
        brsl    $0, fetch_item
1:      ori     $5, $23, 0
        brsl    $0, wait_tag                  # the current item's corners or child pairs

        # fold the current item's nodes into their records: first its leaves' corners
        # through their offsets into the gathered vertices, then the inner nodes' child
        # pairs, gathered (the upper tree) or folded just before (a subtree)
        lqd     $6, 0($20)                    # n_nodes, gather bytes, pairs local, done row
        a       $41, $41, $6
        rotqbyi $16, $6, 8
        ceqi    $16, $16, 0
        selb    $16, $22, $21, $16            # where child pairs are: gathered or folded
        lqd     $7, 32($20)
        rotqbyi $18, $7, 8                    # leaves
        sf      $48, $18, $6                  # inner nodes
        ai      $19, $20, 48
        lqa     $35, k_w3
        lqa     $29, k_lo16
        brz     $18, 6f
leaf_loop:
        lqd     $36, 0($19)                   # corners | dest << 16, offsets, link, count_axis
        and     $39, $36, $29                 # corners
        rotmi   $17, $36, -16                 # dest
        rotqbyi $28, $36, 4
        a       $28, $28, $20                 # its corners' offsets (halfwords), a triangle
        ai      $52, $28, -2                  # a turn; a halfword at A rotated by A - 2
        lqd     $43, 0($28)                   # lands in word 0's low half
        rotqby  $43, $43, $52
        and     $43, $43, $29
        lqx     $37, $21, $43                 # the first corner starts the fold
        ori     $38, $37, 0
        hbrr    .Lfold_br, 3f
3:      ai      $52, $28, -2
        ai      $53, $28, 2
        ai      $54, $28, 4
        lqd     $43, 0($28)
        lqd     $44, 0($53)
        lqd     $45, 0($54)
        rotqby  $43, $43, $52
        rotqby  $44, $44, $28
        rotqby  $45, $45, $53
        and     $43, $43, $29
        and     $44, $44, $29
        and     $45, $45, $29
        lqx     $43, $21, $43
        lqx     $44, $21, $44
        lqx     $45, $21, $45
        ai      $28, $28, 6
        ai      $39, $39, -3
        fcgt    $46, $37, $43
        fcgt    $47, $43, $38
        selb    $37, $37, $43, $46
        selb    $38, $38, $43, $47
        fcgt    $46, $37, $44
        fcgt    $47, $44, $38
        selb    $37, $37, $44, $46
        selb    $38, $38, $44, $47
        fcgt    $46, $37, $45
        fcgt    $47, $45, $38
        selb    $37, $37, $45, $46
        selb    $38, $38, $45, $47
.Lfold_br:
        brnz    $39, 3b
        hbrr    .Lleaf_br, leaf_loop
        rotqbyi $47, $36, 12                  # link into word 3
        selb    $37, $37, $47, $35            # min, link
        selb    $38, $38, $36, $35            # max, count_axis
        a       $17, $17, $22
        stqd    $37, 0($17)
        stqd    $38, 16($17)
        ai      $19, $19, 16
        ai      $18, $18, -1
.Lleaf_br:
        brnz    $18, leaf_loop

        # the next item's block has come while the leaves were folded: where its height's
        # wait is known to be over, its gather runs during the rest of this item
6:      brz     $34, 7f
        ori     $5, $27, 0
        brsl    $0, wait_tag
        lqd     $6, 16($24)                   # its wait: done row EA, count
        rotqbyi $7, $6, 4
        ceq     $8, $6, $32
        ceqi    $9, $7, 0
        or      $8, $8, $9
        brz     $8, 7f                        # not known to be over: gather it later
        ori     $4, $24, 0
        ori     $5, $25, 0
        ori     $6, $27, 0
        brsl    $0, gather
        il      $33, 1
7:      brz     $48, 8f
        hbrr    .Lpair_br, pair_loop
pair_loop:
        lqd     $36, 0($19)                   # dest << 16, pair, link, count_axis
        rotmi   $17, $36, -16
        rotqbyi $28, $36, 4
        a       $28, $28, $16
        lqd     $37, 0($28)
        lqd     $38, 16($28)
        lqd     $43, 32($28)
        lqd     $44, 48($28)
        fcgt    $45, $37, $43
        fcgt    $46, $44, $38
        selb    $37, $37, $43, $45
        selb    $38, $38, $44, $46
        rotqbyi $47, $36, 12
        selb    $37, $37, $47, $35
        selb    $38, $38, $36, $35
        a       $17, $17, $22
        stqd    $37, 0($17)
        stqd    $38, 16($17)
        ai      $19, $19, 16
        ai      $48, $48, -1
.Lpair_br:
        brnz    $48, pair_loop

8:
        # scatter the records; once they are out, count the item done in this SPE's
        # quadword of its height's row
        lqd     $7, 16($20)
        lqd     $8, 32($20)
        rotqbyi $8, $8, 4
        a       $8, $8, $20                   # the scatter list
        rotqbyi $9, $7, 8                     # its bytes
        ai      $3, $23, 2                    # tag 2 + buffer
        il      $5, 0x24                      # putl
        wrch    $MFC_LSA, $22
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $8
        wrch    $MFC_Size, $9
        wrch    $MFC_TagID, $3
        wrch    $MFC_Cmd, $5
        ori     $5, $3, 0
        brsl    $0, wait_tag
        il      $5, 4
        brsl    $0, wait_tag                  # the last count's put has read its buffer
        rotqbyi $7, $7, 12                    # height
        ceq     $8, $7, $49
        selb    $50, $2, $50, $8              # a new height counts from 0
        ori     $49, $7, 0
        ai      $50, $50, 1
        stqa    $50, donebuf
        lqd     $6, 0($20)
        rotqbyi $6, $6, 12
        a       $6, $6, $15
        ila     $5, donebuf
        il      $7, 16
        il      $8, 4
        il      $9, 0x20                      # put
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $6
        wrch    $MFC_Size, $7
        wrch    $MFC_TagID, $8
        wrch    $MFC_Cmd, $9
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
        il      $5, 0xff                      # every tag: nothing left in flight
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

# ---- claim: a range [$3, $4) of items from the shared counter (atomic getllar/putllc):
# (tail - v) >> shift items (at least 1) below the tail, all the rest from it on
claim:
        ila     $5, claimbuf
1:      wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $12
        il      $6, 0xd0                      # getllar
        wrch    $MFC_Cmd, $6
        rdch    $6, $MFC_RdAtomicStat
        lqd     $7, 0($5)
        ori     $3, $7, 0
        ori     $4, $7, 0
        clgt    $6, $10, $7
        brz     $6, 2f                        # none left: nothing to write
        sf      $8, $7, $13                   # tail - v
        sfi     $9, $14, 0
        rotm    $9, $8, $9                    # (tail - v) >> shift
        ceqi    $6, $9, 0
        sf      $9, $6, $9                    # at least 1 (ceqi gives -1)
        cgti    $6, $8, 0
        sf      $52, $7, $10                  # n - v: from the tail on, everything
        selb    $9, $52, $9, $6
        a       $4, $7, $9
        lqd     $6, 0($5)
        a       $6, $6, $9
        stqd    $6, 0($5)
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $12
        il      $6, 0xb4                      # putllc
        wrch    $MFC_Cmd, $6
        rdch    $6, $MFC_RdAtomicStat
        andi    $6, $6, 1
        brnz    $6, 1b                        # reservation lost: again
2:      bi      $0

# ---- fetch_item: the block of item $3 into local store at $4, tag $5 (its index entry
# first)
fetch_item:
        shli    $6, $3, 4
        a       $6, $6, $11
        ila     $7, idxbuf
        il      $8, 16
        il      $9, 6
        wrch    $MFC_LSA, $7
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $6
        wrch    $MFC_Size, $8
        wrch    $MFC_TagID, $9
        il      $8, 0x40                      # get
        wrch    $MFC_Cmd, $8
        il      $8, 64
        wrch    $MFC_WrTagMask, $8
        il      $8, 2
        wrch    $MFC_WrTagUpdate, $8
        rdch    $8, $MFC_RdTagStat
        lqa     $6, idxbuf                    # block EA, bytes
        rotqbyi $7, $6, 4
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

# ---- wait_level: until the height below item block $4's is done (the sum of its done row
# reached its item count), polling the row; $32 remembers the last wait seen over
wait_level:
        lqd     $6, 16($4)
        rotqbyi $7, $6, 4                     # items to wait for
        brz     $7, 2f
        ceq     $8, $6, $32
        brnz    $8, 2f
        ila     $5, pollbuf
1:      il      $8, 256
        il      $9, 7
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $6
        wrch    $MFC_Size, $8
        wrch    $MFC_TagID, $9
        il      $8, 0x40                      # get
        wrch    $MFC_Cmd, $8
        il      $8, 128
        wrch    $MFC_WrTagMask, $8
        il      $8, 2
        wrch    $MFC_WrTagUpdate, $8
        rdch    $8, $MFC_RdTagStat
        ai      $42, $42, 1
        il      $8, 0
        .irp    Q, 0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 208, 224, 240
        lqd     $9, \Q($5)
        a       $8, $8, $9
        .endr
        clgt    $8, $7, $8
        brnz    $8, 1b
        ori     $32, $6, 0
2:      bi      $0

# ---- gather: item block $4's gather list into local store at $5, tag $6
gather:
        lqd     $7, 0($4)
        rotqbyi $7, $7, 4                     # list bytes
        lqd     $8, 32($4)
        a       $8, $8, $4                    # the list
        il      $9, 0x44                      # getl
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $8
        wrch    $MFC_Size, $7
        wrch    $MFC_TagID, $6
        wrch    $MFC_Cmd, $9
        bi      $0
