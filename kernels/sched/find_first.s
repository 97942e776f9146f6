1:
a       $90, $88, $86
lqd     %rx0, 0($90)
lqd     %ry0, 256($90)
lqd     %rz0, 512($90)
lqd     %t0, 768($90)
lqd     %rx1, 16($90)
lqd     %ry1, 272($90)
lqd     %rz1, 528($90)
lqd     %t1, 784($90)
.irp    V, 0, 1
fm      %ax\V, $80, %rx\V
fm      %bx\V, $81, %rx\V
fm      %ay\V, $82, %ry\V
fm      %by\V, $83, %ry\V
fm      %az\V, $84, %rz\V
fm      %bz\V, $85, %rz\V
fcgt    %mx\V, %ax\V, %bx\V
fcgt    %my\V, %ay\V, %by\V
fcgt    %mz\V, %az\V, %bz\V
selb    %lx\V, %ax\V, %bx\V, %mx\V
selb    %hx\V, %bx\V, %ax\V, %mx\V
selb    %ly\V, %ay\V, %by\V, %my\V
selb    %hy\V, %by\V, %ay\V, %my\V
selb    %lz\V, %az\V, %bz\V, %mz\V
selb    %hz\V, %bz\V, %az\V, %mz\V
fcgt    %m1\V, %lx\V, %ly\V
selb    %e1\V, %ly\V, %lx\V, %m1\V
fcgt    %m2\V, %lz\V, ZERO
selb    %e2\V, ZERO, %lz\V, %m2\V
fcgt    %m3\V, %e1\V, %e2\V
selb    %en\V, %e2\V, %e1\V, %m3\V
fcgt    %m4\V, %hx\V, %hy\V
selb    %x1\V, %hx\V, %hy\V, %m4\V
fcgt    %m5\V, %hz\V, %t\V
selb    %x2\V, %hz\V, %t\V, %m5\V
fcgt    %m6\V, %x1\V, %x2\V
selb    %ex\V, %x1\V, %x2\V, %m6\V
fm      %enw\V, %en\V, $113
fm      %exw\V, %ex\V, $114
fcgt    %miss\V, %enw\V, %exw\V
.endr
ai      %idx1, $117, 4
cgt     %act0, $117, $89
cgt     %act1, %idx1, $89
andc    %hit0, %act0, %miss0
andc    %hit1, %act1, %miss1
gb      %g0, %hit0
gb      %g1, %hit1
shli    %g0s, %g0, 4
or      $103, %g0s, %g1
ai      $86, $86, 32
ai      $117, $117, 8
ceqi    $104, $86, 256
! brnz    $103, 2f
! brz     $104, 1b
