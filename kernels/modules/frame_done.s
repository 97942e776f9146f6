# frame_done.s — the end of the frame (the frame driver's last block, modules/frame.s):
# when no tile is left, wait for the last results, write the statistics (STAT_*) to
# STATS + index*128, send 1 to the outbound mailbox and stop with code 0x2000.

        .text
# ---- no tiles left: statistics, end-of-frame message, stop
frame_done:
        il      $80, 12                       # tags 2 and 3: the last results
        wrch    $MFC_WrTagMask, $80
        il      $80, 2
        wrch    $MFC_WrTagUpdate, $80
        rdch    $80, $MFC_RdTagStat
        # the mask sums count -1 twice per child box: sum the lanes, halve
        .irp    V, M1V, EEV
        rotqbyi $81, \V, 8
        a       \V, \V, $81
        rotqbyi $81, \V, 4
        a       \V, \V, $81
        rotmai  \V, \V, -1
        .endr
        shli    $82, S_STEPS, 1               # box tests: two per pair step
        ila     $80, statbuf
        lqa     $81, k_entry
        lqa     $84, vars+V_PACKETS
        shufb   $83, $84, $82, $81
        stqd    $83, STAT_PACKETS($80)        # (packets, box tests, -, -)
        shufb   $83, M1V, EEV, $81
        stqd    $83, STAT_M1SUM($80)
        shufb   $83, S_TRIS, S_CULLED, $81
        stqd    $83, STAT_TRIS($80)
        lqa     $84, vars+V_BMISS
        lqa     $85, vars+V_LEAVES
        shufb   $83, $84, $85, $81
        stqd    $83, STAT_BMISS($80)
        lqa     $85, vars+V_TMISS
        shufb   $83, S_TLOOK, $85, $81
        stqd    $83, STAT_TLOOK($80)
        shufb   $83, S_STEPS, ZERO, $81
        stqd    $83, STAT_BLOOK($80)          # (BVH lookups = pair steps, -)
        lqa     $84, vars+V_MYID
        lqa     $85, vars+V_EASTATS
        shli    $83, $84, 7
        a       $83, $83, $85
        il      $84, 128
        il      $85, 4
        il      $86, 0x20
        wrch    $MFC_LSA, $80
        wrch    $MFC_EAH, ZERO
        wrch    $MFC_EAL, $83
        wrch    $MFC_Size, $84
        wrch    $MFC_TagID, $85
        wrch    $MFC_Cmd, $86
        il      $84, 16
        wrch    $MFC_WrTagMask, $84
        il      $84, 2
        wrch    $MFC_WrTagUpdate, $84
        rdch    $84, $MFC_RdTagStat
        il      $84, 1
        wrch    $SPU_WrOutMbox, $84
        stop    0x2000
