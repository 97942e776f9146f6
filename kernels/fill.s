# fill.s — exercises the multi-SPE runtime without ray tracing: takes 64x64 tiles from the
# shared counter (atomic getllar/putllc increment) and fills each packet block of the
# frame buffer with a pattern, then writes its statistics and says "end of frame".
#
# Same protocol as primary.s: $3 = SPU index, $4 = parameter block EA. For every packet
# of tile T the block's 64 triangle ids are T*64 + packet, the distances 1.0, the shades
# 0x(index)(T)(packet)ff and the reserved words the SPU index, so the host can check that
# every tile was written exactly once and by whom.

        .include "layout.inc"

        .data
        .align 7
params:         .space 128
lockbuf:        .space 128
statbuf:        .space 128
block:          .space 1024
k_inc0:         .long 1, 0, 0, 0
k_pair:         .long 0x00010203, 0x10111213, 0x80808080, 0x80808080
k_splat:        .long 0x00010203, 0x00010203, 0x00010203, 0x00010203

        .text
        .global _start
_start:
        ori     $40, $3, 0                    # SPU index
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
        lqd     $8, PARAM_EA_NODES($5)
        rotqbyi $20, $8, 8                    # frame buffer
        rotqbyi $21, $8, 12                   # tile counter
        lqd     $8, PARAM_WIDTH($5)
        rotqbyi $22, $8, 12                   # number of tiles
        lqd     $8, PARAM_BVH_LOG2($5)
        rotqbyi $23, $8, 8                    # statistics
        il      $30, 0                        # tiles done
        il      $31, 0                        # packets done
        ilhu    $32, 0x3f80                   # 1.0f in every word
        lqa     $33, k_inc0

next_tile:
        ila     $5, lockbuf
1:      wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $21
        il      $6, 0xd0                      # getllar
        wrch    $MFC_Cmd, $6
        rdch    $7, $MFC_RdAtomicStat
        lqd     $8, 0($5)
        a       $9, $8, $33
        stqd    $9, 0($5)
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $21
        il      $6, 0xb4                      # putllc
        wrch    $MFC_Cmd, $6
        rdch    $7, $MFC_RdAtomicStat
        andi    $7, $7, 1
        brnz    $7, 1b
        clgt    $7, $22, $8
        brz     $7, done
        ai      $30, $30, 1
        il      $10, 0                        # packet
packet:
        shli    $11, $8, 6
        a       $11, $11, $10                 # tile*64 + packet
        shli    $12, $8, 8
        or      $12, $12, $10
        shli    $13, $40, 16
        or      $12, $12, $13
        shli    $12, $12, 8
        ori     $12, $12, 0xff                # shade pattern
        lqa     $17, k_splat
        shufb   $24, $11, $11, $17            # splats of the three patterns
        shufb   $25, $12, $12, $17
        shufb   $26, $40, $40, $17
        ila     $14, block
        il      $15, 16
2:      stqd    $24, 0($14)
        stqd    $32, 256($14)
        stqd    $25, 512($14)
        stqd    $26, 768($14)
        ai      $14, $14, 16
        ai      $15, $15, -1
        brnz    $15, 2b
        shli    $19, $11, 10
        a       $19, $19, $20
        ila     $14, block
        wrch    $MFC_LSA, $14
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $19
        il      $6, 1024
        wrch    $MFC_Size, $6
        il      $6, 2
        wrch    $MFC_TagID, $6
        il      $6, 0x20                      # put
        wrch    $MFC_Cmd, $6
        il      $6, 4
        wrch    $MFC_WrTagMask, $6
        il      $6, 2
        wrch    $MFC_WrTagUpdate, $6
        rdch    $6, $MFC_RdTagStat
        ai      $31, $31, 1
        ai      $10, $10, 1
        ceqi    $6, $10, 64
        brz     $6, packet
        br      next_tile

done:
        ila     $5, statbuf
        lqa     $6, k_pair
        shufb   $7, $31, $30, $6              # (packets, tiles, 0, 0)
        stqd    $7, STAT_PACKETS($5)
        shli    $8, $40, 7
        a       $8, $8, $23
        wrch    $MFC_LSA, $5
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $8
        il      $6, 128
        wrch    $MFC_Size, $6
        il      $6, 3
        wrch    $MFC_TagID, $6
        il      $6, 0x20
        wrch    $MFC_Cmd, $6
        il      $6, 8
        wrch    $MFC_WrTagMask, $6
        il      $6, 2
        wrch    $MFC_WrTagUpdate, $6
        rdch    $6, $MFC_RdTagStat
        il      $6, 1
        wrch    $SPU_WrOutMbox, $6
        stop    0x2000
