# clock.s: clock() from the SPU's decrementer, which counts down from 0 from the moment
# the program is loaded, one tick per simulated cycle (the simulator's timebase): the
# ticks elapsed are 0 minus what it reads, so the figure is deterministic and matches
# `spu run`'s cycle count. The program's own CLOCKS_PER_SEC does not describe it: divide
# by the clock frequency (3.2 GHz on the Cell) for seconds. gettimeofday and time are
# PPE-assisted (calls.s), as newlib's SPU port made them; the host answers them from the
# same simulated clock, never its own.

        .text
# clock_t clock(void)
        .global clock
        .type   clock, @function
clock:
        rdch    $3, $SPU_RdDec
        sfi     $3, $3, 0
        bi      $0
        .size   clock, .-clock
