# ppe.s: how the runtime asks the PPE for a library call, and how a program ends.
# __send_to_ppe(signalcode, opcode, data) builds {stop signalcode; (opcode << 24) | data;
# nop; bi $0} on the stack and calls it, as newlib's SPU port did: the PPE serves the call
# and resumes after the data word; the reply is data's first quadword {rc, 0, 0, errno}.

        .text
        .global __send_to_ppe
        .type   __send_to_ppe, @function
__send_to_ppe:
        stqd    $0, 16($1)
        stqd    $1, -48($1)
        ai      $1, $1, -48
        shli    $4, $4, 24
        ilhu    $6, 0x00ff
        iohl    $6, 0xffff
        and     $6, $5, $6
        or      $4, $4, $6              # the data word
        lqr     $7, .Lstub_tail         # {0, 0, nop, bi $0}
        cwd     $8, 0($1)               # insert word 0 (the stop)
        shufb   $7, $3, $7, $8
        cwd     $8, 4($1)               # insert word 1 (the data)
        shufb   $7, $4, $7, $8
        stqd    $7, 32($1)
        ai      $9, $1, 32
        sync
        bisl    $0, $9
        lqd     $7, 0($5)               # {rc, 0, 0, errno}
        rotqbyi $8, $7, 12
        ila     $9, errno
        lqd     $10, 0($9)
        cwd     $11, 0($9)
        shufb   $10, $8, $10, $11
        stqd    $10, 0($9)
        ori     $3, $7, 0
        ai      $1, $1, 48
        lqd     $0, 16($1)
        bi      $0
        .size   __send_to_ppe, .-__send_to_ppe

# exit(status), _exit(status): stop 0x2000 | (status & 0xff), which elfspe turns into
# the process's exit status. The stop code is built at run time as __send_to_ppe builds
# its stop.
        .global exit
        .type   exit, @function
        .global _exit
        .type   _exit, @function
exit:
_exit:
        andi    $3, $3, 0xff
        il      $8, 0x2000
        or      $3, $3, $8
        lqr     $7, .Lstub_tail
        ai      $1, $1, -32
        cwd     $8, 0($1)
        shufb   $7, $3, $7, $8
        stqd    $7, 0($1)
        sync
        bi      $1
        .size   exit, .-exit

        .section .rodata
        .align  4
.Lstub_tail:
        .long   0, 0, 0x4020007f, 0x35000000

# errno, set by every PPE-assisted call (0 on success), as newlib's stubs set it.
        .data
        .align  4
        .global errno
        .type   errno, @object
errno:  .long   0, 0, 0, 0
        .size   errno, 16

# The standard streams: a FILE * here is the PPE's stream number.
        .global stdin
        .global stdout
        .global stderr
        .align  4
stdin:  .long   1, 0, 0, 0
stdout: .long   2, 0, 0, 0
stderr: .long   3, 0, 0, 0
