# output.s — packet output: shade the packet's rays and send its 1 KiB result block.
#
# Per packet the block goes to FB + (tile*64 + packet)*1024:
#   +0 hit triangle index[64] (0xffffffff = miss), +256 distance t[64] (along the
#   unnormalised camera ray), +512 eye-light shade 0xGGGGGGff[64], +768 reserved (zero).
# Two blocks alternate in outbuf so a packet's DMA overlaps the next packet's work; then
# the next packet (modules/raygen.s) or the next tile (modules/frame.s).

        .text
# ---- the packet is done: shade and send its results
        .align  3
packet_done:
        # (scheduled into even/odd pairs) wait until this buffer's previous transfer (tag
        # 2 + OUTSEL/1024) is done; per ray the hit, t and the shade |n.d / |n| * 1/|d||
        # * 256 clamped to 255, gray and opaque, background for misses; put the 1 KiB block
        # to FB + (tile*64 + packet)*1024
        nop
        lqa     $67, vars+V_PACKETS
        ai      $68, $67, 1
        lnop
        nop
        stqa    $68, vars+V_PACKETS
        il      $69, 1
        lqa     $66, vars+V_OUTSEL
        ila     $70, outbuf
        lnop
        rotmi   $71, $66, -10
        lnop
        a       $80, $70, $66
        lnop
        ai      $81, $71, 2
        lnop
        shl     $72, $69, $81
        lnop
        nop
        wrch    $MFC_WrTagMask, $72
        il      $73, 2
        lnop
        nop
        wrch    $MFC_WrTagUpdate, $73
        nop
        rdch    $74, $MFC_RdTagStat
        ori     $75, RAYS, 0
        lqd     $76, 0+2048($75)
        nop
        lqd     $77, 0+2304($75)
        nop
        lqd     $78, 16+2048($75)
        nop
        lqd     $79, 16+2304($75)
        nop
        lqd     $82, 32+2048($75)
        nop
        lqd     $83, 32+2304($75)
        nop
        lqd     $84, 48+2048($75)
        fm      $85, $76, $77
        lqd     $86, 48+2304($75)
        nop
        lqd     $87, 64+2048($75)
        fm      $88, $78, $79
        lqd     $89, 64+2304($75)
        nop
        lqd     $90, 80+2048($75)
        fm      $91, $82, $83
        lqd     $92, 80+2304($75)
        nop
        lqd     $94, 96+2048($75)
        fm      $95, $84, $86
        lqd     $96, 96+2304($75)
        nop
        lqd     $97, 112+2048($75)
        fm      $98, $87, $89
        lqd     $99, 112+2304($75)
        nop
        lqa     $100, k_abs
        fm      $101, $90, $92
        lqa     $102, k_c255
        nop
        lqa     $103, k_shade
        fm      $104, $94, $96
        lqd     $105, 0+1792($75)
        nop
        lqd     $106, 16+1792($75)
        fm      $107, $97, $99
        lqd     $108, 32+1792($75)
        and     $109, $85, $100
        lqd     $110, 48+1792($75)
        and     $111, $88, $100
        lqd     $112, 64+1792($75)
        and     $113, $91, $100
        lqd     $114, 80+1792($75)
        and     $115, $95, $100
        lqd     $116, 96+1792($75)
        and     $117, $98, $100
        lqd     $118, 112+1792($75)
        and     $119, $101, $100
        lqa     $120, k_bg
        and     $121, $104, $100
        lqd     $122, 0+1536($75)
        and     $123, $107, $100
        lqd     $124, 16+1536($75)
        cfltu   $125, $109, 8
        lqd     $126, 32+1536($75)
        cfltu   $127, $111, 8
        lqd     $67, 48+1536($75)
        cfltu   $68, $113, 8
        lqd     $70, 64+1536($75)
        cfltu   $71, $115, 8
        lqd     $69, 80+1536($75)
        cfltu   $72, $117, 8
        lqd     $73, 96+1536($75)
        cfltu   $74, $119, 8
        lqd     $77, 112+1536($75)
        cfltu   $76, $121, 8
        stqd    $105, 0($80)
        cfltu   $78, $123, 8
        stqd    $122, 256($80)
        clgt    $79, $125, $102
        stqd    $106, 16($80)
        clgt    $83, $127, $102
        stqd    $124, 272($80)
        clgt    $82, $68, $102
        stqd    $108, 32($80)
        clgt    $84, $71, $102
        stqd    $126, 288($80)
        clgt    $86, $72, $102
        stqd    $110, 48($80)
        clgt    $89, $74, $102
        stqd    $67, 304($80)
        clgt    $87, $76, $102
        stqd    $112, 64($80)
        clgt    $92, $78, $102
        stqd    $70, 320($80)
        selb    $90, $125, $102, $79
        stqd    $114, 80($80)
        selb    $94, $127, $102, $83
        stqd    $69, 336($80)
        selb    $96, $68, $102, $82
        shufb   $99, $90, $90, $103
        selb    $97, $71, $102, $84
        shufb   $85, $94, $94, $103
        selb    $88, $72, $102, $86
        shufb   $91, $96, $96, $103
        selb    $95, $74, $102, $89
        shufb   $98, $97, $97, $103
        selb    $101, $76, $102, $87
        shufb   $104, $88, $88, $103
        selb    $107, $78, $102, $92
        shufb   $109, $95, $95, $103
        ceqi    $111, $105, -1
        shufb   $113, $101, $101, $103
        ceqi    $115, $106, -1
        shufb   $117, $107, $107, $103
        ceqi    $119, $108, -1
        stqd    $116, 96($80)
        ceqi    $121, $110, -1
        stqd    $73, 352($80)
        ceqi    $123, $112, -1
        stqd    $118, 112($80)
        ceqi    $122, $114, -1
        stqd    $77, 368($80)
        ceqi    $124, $116, -1
        lnop
        ceqi    $126, $118, -1
        lnop
        selb    $67, $99, $120, $111
        lnop
        selb    $70, $85, $120, $115
        lnop
        selb    $125, $91, $120, $119
        stqd    $67, 512($80)
        selb    $79, $98, $120, $121
        stqd    $70, 528($80)
        selb    $127, $104, $120, $123
        stqd    $125, 544($80)
        selb    $83, $109, $120, $122
        stqd    $79, 560($80)
        selb    $69, $113, $120, $124
        stqd    $127, 576($80)
        selb    $82, $117, $120, $126
        stqd    $83, 592($80)
        nop
        stqd    $69, 608($80)
        nop
        stqd    $82, 624($80)
        nop
        lnop
        il      $68, 1024
        lqd     $90, 128+2048($75)
        il      $71, 0x20
        lqd     $84, 128+2304($75)
        nop
        lqd     $94, 144+2048($75)
        nop
        lqd     $86, 144+2304($75)
        nop
        lqd     $72, 160+2048($75)
        nop
        lqd     $96, 160+2304($75)
        nop
        lqd     $89, 176+2048($75)
        fm      $74, $90, $84
        lqd     $97, 176+2304($75)
        nop
        lqd     $87, 192+2048($75)
        fm      $76, $94, $86
        lqd     $88, 192+2304($75)
        nop
        lqd     $92, 208+2048($75)
        fm      $78, $72, $96
        lqd     $95, 208+2304($75)
        nop
        lqd     $105, 224+2048($75)
        fm      $101, $89, $97
        lqd     $106, 224+2304($75)
        and     $107, $74, $100
        lqd     $108, 240+2048($75)
        fm      $110, $87, $88
        lqd     $73, 240+2304($75)
        and     $112, $76, $100
        lqd     $114, CTX_TILE64(RAYS)
        fm      $77, $92, $95
        lqd     $116, 128+1792($75)
        and     $118, $78, $100
        lqd     $111, 144+1792($75)
        fm      $99, $105, $106
        lqd     $115, 160+1792($75)
        and     $85, $101, $100
        lqd     $119, 176+1792($75)
        fm      $91, $108, $73
        lqd     $67, 192+1792($75)
        and     $121, $110, $100
        lqd     $98, 208+1792($75)
        and     $70, $77, $100
        lqd     $104, 224+1792($75)
        cfltu   $123, $107, 8
        lqd     $125, 240+1792($75)
        and     $122, $99, $100
        lqd     $93, CTX_PACKET(RAYS)
        cfltu   $109, $112, 8
        lqd     $79, 128+1536($75)
        and     $124, $91, $100
        lqd     $113, 144+1536($75)
        cfltu   $127, $118, 8
        lqd     $126, 160+1536($75)
        cfltu   $117, $85, 8
        lqd     $83, 176+1536($75)
        cfltu   $69, $121, 8
        lqd     $82, 192+1536($75)
        cfltu   $90, $70, 8
        lqd     $84, 208+1536($75)
        cfltu   $94, $122, 8
        lqd     $86, 224+1536($75)
        cfltu   $96, $124, 8
        lqd     $72, 240+1536($75)
        clgt    $89, $123, $102
        lqa     $97, vars+V_EAFB
        clgt    $74, $109, $102
        stqd    $116, 128($80)
        clgt    $88, $127, $102
        stqd    $79, 384($80)
        clgt    $87, $117, $102
        stqd    $111, 144($80)
        clgt    $76, $69, $102
        stqd    $113, 400($80)
        clgt    $92, $90, $102
        stqd    $115, 160($80)
        clgt    $95, $94, $102
        stqd    $126, 416($80)
        clgt    $78, $96, $102
        stqd    $119, 176($80)
        selb    $105, $123, $102, $89
        stqd    $83, 432($80)
        selb    $106, $109, $102, $74
        stqd    $67, 192($80)
        selb    $101, $127, $102, $88
        shufb   $73, $105, $105, $103
        selb    $108, $117, $102, $87
        shufb   $110, $106, $106, $103
        selb    $77, $69, $102, $76
        shufb   $107, $101, $101, $103
        selb    $99, $90, $102, $92
        shufb   $112, $108, $108, $103
        selb    $91, $94, $102, $95
        shufb   $100, $77, $77, $103
        selb    $118, $96, $102, $78
        shufb   $85, $99, $99, $103
        ori     $121, $114, 0
        shufb   $70, $91, $91, $103
        ceqi    $122, $116, -1
        shufb   $124, $118, $118, $103
        ceqi    $75, $111, -1
        stqd    $82, 448($80)
        ceqi    $79, $115, -1
        stqd    $98, 208($80)
        ceqi    $113, $119, -1
        stqd    $84, 464($80)
        ceqi    $126, $67, -1
        stqd    $104, 224($80)
        ceqi    $89, $98, -1
        stqd    $86, 480($80)
        ceqi    $123, $104, -1
        stqd    $125, 240($80)
        ceqi    $83, $125, -1
        stqd    $72, 496($80)
        selb    $74, $73, $120, $122
        lnop
        selb    $109, $110, $120, $75
        lnop
        selb    $127, $107, $120, $79
        stqd    $74, 640($80)
        selb    $88, $112, $120, $113
        stqd    $109, 656($80)
        selb    $105, $100, $120, $126
        stqd    $127, 672($80)
        selb    $117, $85, $120, $89
        stqd    $88, 688($80)
        selb    $87, $70, $120, $123
        stqd    $105, 704($80)
        selb    $106, $124, $120, $83
        stqd    $117, 720($80)
        a       $69, $121, $93
        stqd    $87, 736($80)
        nop
        stqd    $106, 752($80)
        shli    $76, $69, 10
        lnop
        a       $101, $76, $97
        lnop
        nop
        wrch    $MFC_LSA, $80
        nop
        wrch    $MFC_EAH, ZERO
        nop
        wrch    $MFC_EAL, $101
        nop
        wrch    $MFC_Size, $68
        nop
        wrch    $MFC_TagID, $81
        nop
        wrch    $MFC_Cmd, $71
        xor     $92, $66, $68
        lnop
        nop
        stqa    $92, vars+V_OUTSEL
        br      packet_start                  # the context's next packet (modules/frame.s)
