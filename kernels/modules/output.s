# output.s — packet output: shade the packet's rays and send its 1 KiB result block.
#
# Per packet the block goes to FB + (tile*64 + packet)*1024:
#   +0 hit triangle index[64] (0xffffffff = miss), +256 distance t[64] (along the
#   unnormalised camera ray), +512 eye-light shade 0xGGGGGGff[64], +768 reserved (zero).
# A shaded frame (SHADE) sends the first 512 bytes only: its colours are shade.s's.
# The rays are the current packet context's (RAYS) and so are the tile and packet numbers.
# Two blocks alternate in outbuf so a packet's DMA overlaps the next packet's work; then
# the context's next packet (packet_start, modules/frame.s).

        .text
# ---- the packet is done: shade and send its results
        .align  3
packet_done:
        .ifdef  SHADE                         # --shade simple: modules/shade.s first
        .ifdef  REFLECT                       # --shade reflect: modules/reflect.s, which
        hbrr    .Lpd_shade_br, reflect_packet # calls shade.s per level
        .else
        hbrr    .Lpd_shade_br, shade_packet
        .endif
        lqa     $66, sv_trace                 # (a shadow packet: modules/shadow.s)
        brnz    $66, shadow_done
        .ifdef  REFLECT
        lqa     $66, rf_trace                 # (a reflected ray: modules/reflect.s)
        brnz    $66, reflect_ray_done
        .endif
        lqd     $69, CTX_TILE64(RAYS)
        lqd     $70, CTX_PACKET(RAYS)
        ori     $68, RAYS, 0
        a       $69, $69, $70
.Lpd_shade_br:
        .ifdef  REFLECT
        brsl    $0, reflect_packet
        .else
        brsl    $0, shade_packet
        .endif
        nop
        .endif
        .sched  pool=67-79,82-92,94-127 scratch=66-127
        lqa     %np, vars+V_PACKETS
        ai      %np1, %np, 1
      ! stqa    %np1, vars+V_PACKETS
        lqa     $66, vars+V_OUTSEL
        ila     %ob, outbuf
        a       $80, %ob, $66
        rotmi   %tg, $66, -10
        ai      $81, %tg, 2
        il      %one, 1
        shl     %mask, %one, $81
      ! wrch    $MFC_WrTagMask, %mask
        il      %two, 2
      ! wrch    $MFC_WrTagUpdate, %two
      ! rdch    %st, $MFC_RdTagStat
        ori     %base, RAYS, 0
        hbrr    .Lpd_next_br, packet_start
        .ifdef  SHADE
        # a shaded frame's colours went to the colour buffer (modules/shade.s): the block
        # carries the hits and distances only, its first 512 bytes
        .irp    J, 0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 208, 224, 240
        lqd     %id\J, \J+1792(%base)
        lqd     %t\J, \J+1536(%base)
      ~ stqd    %id\J, \J($80)
      ~ stqd    %t\J, \J+256($80)
        .endr
        .else
        lqa     %bg, k_bg
        lqa     %pat, k_shade
        lqa     %abs, k_abs
        lqa     %c255, k_c255
        .irp    J, 0, 16, 32, 48, 64, 80, 96, 112
        lqd     %id\J, \J+1792(%base)
        lqd     %nd\J, \J+2048(%base)
        lqd     %iv\J, \J+2304(%base)
        lqd     %t\J, \J+1536(%base)
        fm      %c\J, %nd\J, %iv\J
        ceqi    %miss\J, %id\J, -1
        and     %ca\J, %c\J, %abs
        cfltu   %s\J, %ca\J, 8
        clgt    %big\J, %s\J, %c255
        selb    %sc\J, %s\J, %c255, %big\J
        shufb   %g\J, %sc\J, %sc\J, %pat
        selb    %rgba\J, %g\J, %bg, %miss\J
      ~ stqd    %id\J, \J($80)
      ~ stqd    %t\J, \J+256($80)
      ~ stqd    %rgba\J, \J+512($80)
        .endr
      ! lnop
        .irp    J, 128, 144, 160, 176, 192, 208, 224, 240
        lqd     %id\J, \J+1792(%base)
        lqd     %nd\J, \J+2048(%base)
        lqd     %iv\J, \J+2304(%base)
        lqd     %t\J, \J+1536(%base)
        fm      %c\J, %nd\J, %iv\J
        ceqi    %miss\J, %id\J, -1
        and     %ca\J, %c\J, %abs
        cfltu   %s\J, %ca\J, 8
        clgt    %big\J, %s\J, %c255
        selb    %sc\J, %s\J, %c255, %big\J
        shufb   %g\J, %sc\J, %sc\J, %pat
        selb    %rgba\J, %g\J, %bg, %miss\J
      ~ stqd    %id\J, \J($80)
      ~ stqd    %t\J, \J+256($80)
      ~ stqd    %rgba\J, \J+512($80)
        .endr
        .endif
        lqd     %tile, CTX_TILE64(RAYS)   # tile * 64
        lqd     $93, CTX_PACKET(RAYS)
        lqa     %eafb, vars+V_EAFB
        a       %q2, %tile, $93
        shli    %q3, %q2, 10
        a       %ea, %q3, %eafb
        .ifdef  SHADE
        il      %size, 512
        il      %block, 1024
        xor     %os, $66, %block
        .else
        il      %size, 1024
        xor     %os, $66, %size
        .endif
        il      %cmd, 0x20
      ! wrch    $MFC_LSA, $80
      ! wrch    $MFC_EAH, ZERO
      ! wrch    $MFC_EAL, %ea
      ! wrch    $MFC_Size, %size
      ! wrch    $MFC_TagID, $81
      ! wrch    $MFC_Cmd, %cmd
      ! stqa    %os, vars+V_OUTSEL
.Lpd_next_br:
      ! br      packet_start                  # the context's next packet (modules/frame.s)
        .endsched
