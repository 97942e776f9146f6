# dma_stream.s — the memory-bandwidth benchmark: streams 16 KiB blocks from main memory
# into local store as fast as the MFC takes them, four gets in flight (one per tag), the
# way the published SPE-to-memory bandwidth measurements do; or streams them out with
# puts. The host times it on 1 to 64 SPEs at once (loader/src/membench.rs,
# docs/memory-model.md).
#
# $3 = effective address of this SPE's stream (16 KiB aligned), $4 = blocks to move
# (a multiple of 4, at least 4), $5 = the MFC command: 0x40 (get) or 0x20 (put).

        .text
        .global _start
_start:
        il      $2, 0
        ila     $10, 0x4000                   # block size, and the buffer stride
        ila     $11, 0x10000                  # first buffer: tags 0..3 use 0x10000..0x1ffff
        il      $12, 0                        # blocks issued
        il      $13, 0                        # tag of the next block
        ori     $14, $3, 0                    # effective address of the next block
        il      $15, 4                        # blocks before the first wait
issue:
        shli    $16, $13, 14
        a       $16, $16, $11                 # the tag's buffer
        wrch    $MFC_LSA, $16
        wrch    $MFC_EAH, $2
        wrch    $MFC_EAL, $14
        wrch    $MFC_Size, $10
        wrch    $MFC_TagID, $13
        wrch    $MFC_Cmd, $5
        a       $14, $14, $10
        ai      $12, $12, 1
        ai      $13, $13, 1
        andi    $13, $13, 3
        ceq     $17, $12, $4
        brnz    $17, drain
        ai      $15, $15, -1
        brnz    $15, issue
        # the next tag's block must be in before its buffer is reused
        il      $15, 1
        il      $18, 1
        shl     $18, $18, $13
        wrch    $MFC_WrTagMask, $18
        il      $19, 2
        wrch    $MFC_WrTagUpdate, $19
        rdch    $19, $MFC_RdTagStat
        br      issue
drain:
        il      $18, 15
        wrch    $MFC_WrTagMask, $18
        il      $19, 2
        wrch    $MFC_WrTagUpdate, $19
        rdch    $19, $MFC_RdTagStat
        stop    0x2000
