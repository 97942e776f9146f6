.Ltri_hit:
        lqd     $86, TRI_N_U($84)              # (n_u, n_v, n_d, k)
        lqd     $87, TRI_B_NU($84)             # (b_nu, b_nv, b_d, -)
        lqd     $88, TRI_C_NU($84)             # (c_nu, c_nv, c_d, -)
        rotqbyi $89, $86, 12                  # k
        shli    $89, $89, 4
        ila     $90, k_axoff
        lqx     $91, $90, $89                 # (k, u, v) array offsets
        ila     $90, k_kuv
        lqx     $92, $90, $89
        shufb   $92, ORIG, ORIG, $92          # origin in (k, u, v) order
        # per-triangle splats, live through the ray loop
        shufb   $68, $86, $86, PAT0            # n_u
        shufb   $69, $86, $86, PAT1            # n_v
        shufb   $93, $86, $86, PAT2           # n_d
        shufb   $71, $87, $87, PAT0            # b_nu
        shufb   $72, $87, $87, PAT1            # b_nv
        shufb   $73, $87, $87, PAT2            # b_d
        shufb   $74, $88, $88, PAT0            # c_nu
        shufb   $75, $88, $88, PAT1            # c_nv
        shufb   $120, $88, $88, PAT2          # c_d
        shufb   $94, $92, $92, PAT0           # o_k
        shufb   $121, $92, $92, PAT1          # o_u
        shufb   $122, $92, $92, PAT2          # o_v
        fs      $70, $93, $94
        fnms    $70, $68, $121, $70
        fnms    $70, $69, $122, $70              # num = n_d - o_k - n_u o_u - n_v o_v
        fm      $95, $68, $68
        fma     $95, $69, $69, $95
        fa      $95, $95, ONE
        frsqest $96, $95
        fi      $123, $95, $96                # 1/|n|, n = (1, n_u, n_v) in (k, u, v)
        shufb   $124, $66, $66, PAT0          # triangle index
        ila     $97, ray_dx
        rotqbyi $98, $91, 4
        rotqbyi $99, $91, 8
        a       $125, $97, $91                # base of d_k
        a       $126, $97, $98                # d_u
        a       $127, $97, $99                # d_v
        # frustum culling with the packet's corner rays (0, 7, 56, 63)
        ila     $97, corners
        rotmi   $100, $91, -4
        rotmi   $101, $98, -4
        rotmi   $102, $99, -4
        lqx     $103, $97, $100               # corner d_k
        lqx     $104, $97, $101               # corner d_u
        lqx     $105, $97, $102               # corner d_v
        fma     $106, $68, $104, $103
        fma     $106, $69, $105, $106          # den = n.d
        frest   $107, $106
        fi      $107, $106, $107
        fnms    $108, $106, $107, ONE
        fma     $107, $108, $107, $107
        fm      $107, $70, $107                # t
        fma     $108, $107, $104, $121        # hit u
        fma     $109, $107, $105, $122        # hit v
        fma     $110, $71, $108, $73
        fma     $110, $72, $109, $110          # beta
        fma     $111, $74, $108, $120
        fma     $111, $75, $109, $111          # gamma
        fa      $112, $110, $111
        fcgt    $113, $107, ZERO              # in front
        fcgt    $114, ZERO, $110
        fcgt    $115, ZERO, $111
        fcgt    $116, $112, ONE
        and     $114, $114, $113
        and     $115, $115, $113
        and     $116, $116, $113
        gb      $113, $113
        gb      $114, $114
        gb      $115, $115
        gb      $116, $116
        ceqi    $113, $113, 0                 # every corner behind
        ceqi    $114, $114, 15                # every corner outside one edge
        ceqi    $115, $115, 15
        ceqi    $116, $116, 15
        or      $113, $113, $114
        or      $115, $115, $116
        or      $113, $113, $115
        sf      S_CULLED, $113, S_CULLED      # +1 when culled
! brnz    $113, tri_next
        ai      S_TRIS, S_TRIS, 1

        # the active rays, four vectors (16 rays) per pass, from FIRST's group on
        rotmi   $119, FIRST, -4
        shli    $119, $119, 6                 # byte offset of the first group
