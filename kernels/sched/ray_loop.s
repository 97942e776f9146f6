ray_loop:
ila     %tb, ray_t
ila     %ib, ray_id
ila     %nb, ray_nd
a       %tp, %tb, $119
a       %ip, %ib, $119
a       %np, %nb, $119
lqx     %dk0, $125, $119
lqx     %du0, $126, $119
lqx     %dv0, $127, $119
ai      $119, $119, 16
fma     %den0, $68, %du0, %dk0
fma     %den0, $69, %dv0, %den0
frest   %y0, %den0
fi      %y0, %den0, %y0
fnms    %e0, %den0, %y0, ONE
fma     %e0, %e0, %y0, %y0
fm      %t0, $70, %e0
fma     %du0, %t0, %du0, $121
fma     %dv0, %t0, %dv0, $122
fma     %be0, $71, %du0, $73
fma     %ga0, $74, %du0, $120
fma     %be0, $72, %dv0, %be0
fma     %ga0, $75, %dv0, %ga0
lqd     %to0, 0(%tp)
fa      %bg0, %be0, %ga0
fcgt    %o10, $76, %be0
fcgt    %o20, $76, %ga0
fcgt    %o30, %bg0, $77
fcgt    %cl0, %to0, %t0
fcgt    %cl20, %t0, ZERO
or      %o10, %o10, %o20
and     %cl0, %cl0, %cl20
or      %o10, %o10, %o30
andc    %hit0, %cl0, %o10
lqd     %io0, 0(%ip)
lqd     %no0, 0(%np)
fm      %nd0, %den0, $123
selb    %to0, %to0, %t0, %hit0
selb    %io0, %io0, $124, %hit0
selb    %no0, %no0, %nd0, %hit0
~ stqd    %to0, 0(%tp)
~ stqd    %io0, 0(%ip)
~ stqd    %no0, 0(%np)
lqx     %dk1, $125, $119
lqx     %du1, $126, $119
lqx     %dv1, $127, $119
ai      $119, $119, 16
fma     %den1, $68, %du1, %dk1
fma     %den1, $69, %dv1, %den1
frest   %y1, %den1
fi      %y1, %den1, %y1
fnms    %e1, %den1, %y1, ONE
fma     %e1, %e1, %y1, %y1
fm      %t1, $70, %e1
fma     %du1, %t1, %du1, $121
fma     %dv1, %t1, %dv1, $122
fma     %be1, $71, %du1, $73
fma     %ga1, $74, %du1, $120
fma     %be1, $72, %dv1, %be1
fma     %ga1, $75, %dv1, %ga1
lqd     %to1, 16(%tp)
fa      %bg1, %be1, %ga1
fcgt    %o11, $76, %be1
fcgt    %o21, $76, %ga1
fcgt    %o31, %bg1, $77
fcgt    %cl1, %to1, %t1
fcgt    %cl21, %t1, ZERO
or      %o11, %o11, %o21
and     %cl1, %cl1, %cl21
or      %o11, %o11, %o31
andc    %hit1, %cl1, %o11
lqd     %io1, 16(%ip)
lqd     %no1, 16(%np)
fm      %nd1, %den1, $123
selb    %to1, %to1, %t1, %hit1
selb    %io1, %io1, $124, %hit1
selb    %no1, %no1, %nd1, %hit1
~ stqd    %to1, 16(%tp)
~ stqd    %io1, 16(%ip)
~ stqd    %no1, 16(%np)
lqx     %dk2, $125, $119
lqx     %du2, $126, $119
lqx     %dv2, $127, $119
ai      $119, $119, 16
fma     %den2, $68, %du2, %dk2
fma     %den2, $69, %dv2, %den2
frest   %y2, %den2
fi      %y2, %den2, %y2
fnms    %e2, %den2, %y2, ONE
fma     %e2, %e2, %y2, %y2
fm      %t2, $70, %e2
fma     %du2, %t2, %du2, $121
fma     %dv2, %t2, %dv2, $122
fma     %be2, $71, %du2, $73
fma     %ga2, $74, %du2, $120
fma     %be2, $72, %dv2, %be2
fma     %ga2, $75, %dv2, %ga2
lqd     %to2, 32(%tp)
fa      %bg2, %be2, %ga2
fcgt    %o12, $76, %be2
fcgt    %o22, $76, %ga2
fcgt    %o32, %bg2, $77
fcgt    %cl2, %to2, %t2
fcgt    %cl22, %t2, ZERO
or      %o12, %o12, %o22
and     %cl2, %cl2, %cl22
or      %o12, %o12, %o32
andc    %hit2, %cl2, %o12
lqd     %io2, 32(%ip)
lqd     %no2, 32(%np)
fm      %nd2, %den2, $123
selb    %to2, %to2, %t2, %hit2
selb    %io2, %io2, $124, %hit2
selb    %no2, %no2, %nd2, %hit2
~ stqd    %to2, 32(%tp)
~ stqd    %io2, 32(%ip)
~ stqd    %no2, 32(%np)
lqx     %dk3, $125, $119
lqx     %du3, $126, $119
lqx     %dv3, $127, $119
ai      $119, $119, 16
fma     %den3, $68, %du3, %dk3
fma     %den3, $69, %dv3, %den3
frest   %y3, %den3
fi      %y3, %den3, %y3
fnms    %e3, %den3, %y3, ONE
fma     %e3, %e3, %y3, %y3
fm      %t3, $70, %e3
fma     %du3, %t3, %du3, $121
fma     %dv3, %t3, %dv3, $122
fma     %be3, $71, %du3, $73
fma     %ga3, $74, %du3, $120
fma     %be3, $72, %dv3, %be3
fma     %ga3, $75, %dv3, %ga3
lqd     %to3, 48(%tp)
fa      %bg3, %be3, %ga3
fcgt    %o13, $76, %be3
fcgt    %o23, $76, %ga3
fcgt    %o33, %bg3, $77
fcgt    %cl3, %to3, %t3
fcgt    %cl23, %t3, ZERO
or      %o13, %o13, %o23
and     %cl3, %cl3, %cl23
or      %o13, %o13, %o33
andc    %hit3, %cl3, %o13
lqd     %io3, 48(%ip)
lqd     %no3, 48(%np)
fm      %nd3, %den3, $123
selb    %to3, %to3, %t3, %hit3
selb    %io3, %io3, $124, %hit3
selb    %no3, %no3, %nd3, %hit3
~ stqd    %to3, 48(%tp)
~ stqd    %io3, 48(%ip)
~ stqd    %no3, 48(%np)
ceqi    $112, $119, 256
! brz     $112, ray_loop
