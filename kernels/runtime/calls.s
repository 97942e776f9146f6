# calls.s: the C library's entry points that the PPE serves (libspe2's C99 and POSIX.1
# classes, docs/running-programs.md), each with the SPU ABI's calling convention: the
# arguments in $3..., the result in $3, $80..$127 kept. A call stores its arguments, one
# per quadword, in a block on its stack frame and hands the block to __send_to_ppe.

        .set    C99, 0x2100
        .set    POSIX1, 0x2101

# The entry of NAME: a global function that saves its link register in the caller's frame.
        .macro  ENTRY name
        .text
        .global \name
        .type   \name, @function
\name:
        stqd    $0, 16($1)
        .endm

# Stores COUNT argument registers from $.Lreg on, one per quadword from .Loff($1) on,
# leaving .Lreg and .Loff past them.
        .macro  STORE_ARGS count
        .rept   \count
        stqd    .Lreg, .Loff($1)
        .set    .Lreg, .Lreg + 1
        .set    .Loff, .Loff + 16
        .endr
        .endm

# NAME(a0, ..., a[NARGS-1]): opcode OP of CLASS.
        .macro  PPE_CALL name, class, op, nargs
        ENTRY   \name
        stqd    $1, -128($1)
        ai      $1, $1, -128
        .set    .Lreg, 3
        .set    .Loff, 32
        STORE_ARGS \nargs
        il      $3, \class
        il      $4, \op
        ai      $5, $1, 32
        brsl    $0, __send_to_ppe
        ai      $1, $1, 128
        lqd     $0, 16($1)
        bi      $0
        .size   \name, .-\name
        .endm

# NAME(a0, ..., a[NAMED-1], ...): the printf family. The unnamed arguments' registers
# ($3+NAMED..$74) are saved just below the caller's frame, so that the va_list {next
# argument, caller's stack} walks them and then, past the caller's 32-byte link area,
# the arguments the caller passed on its stack; the block holds the named arguments and
# the va_list (32 bytes).
        .macro  PPE_VACALL name, op, named
        ENTRY   \name
        .set    .Lsave, (72 - \named) * 16
        .set    .Lframe, 32 + 96 + .Lsave
        stqd    $1, -.Lframe($1)
        il      $75, .Lframe            # too big for ai's immediate
        sf      $1, $75, $1
        .set    .Lreg, 3
        .set    .Loff, 32
        STORE_ARGS \named
        .set    .Loff, 128
        STORE_ARGS 72 - \named
        .set    .Lva, 32 + 16 * \named
        ai      $6, $1, 128             # the first unnamed argument
        stqd    $6, .Lva($1)
        il      $6, .Lframe             # the caller's stack
        a       $6, $1, $6
        stqd    $6, .Lva + 16($1)
        il      $3, C99
        il      $4, \op
        ai      $5, $1, 32
        brsl    $0, __send_to_ppe
        il      $6, .Lframe
        a       $1, $1, $6
        lqd     $0, 16($1)
        bi      $0
        .size   \name, .-\name
        .endm

# NAME(a0, ..., a[NAMED-1], va_list ap): the vprintf family; ap points to the 32-byte
# va_list, copied into the block after the named arguments.
        .macro  PPE_VCALL name, op, named
        ENTRY   \name
        stqd    $1, -128($1)
        ai      $1, $1, -128
        .set    .Lreg, 3
        .set    .Loff, 32
        STORE_ARGS \named
        lqd     $6, 0(.Lreg)
        lqd     $7, 16(.Lreg)
        stqd    $6, .Loff($1)
        stqd    $7, .Loff + 16($1)
        il      $3, C99
        il      $4, \op
        ai      $5, $1, 32
        brsl    $0, __send_to_ppe
        ai      $1, $1, 128
        lqd     $0, 16($1)
        bi      $0
        .size   \name, .-\name
        .endm

        # C99 (libspe2's SPE_C99_* opcodes)
        PPE_CALL    clearerr, C99, 1, 1
        PPE_CALL    fclose, C99, 2, 1
        PPE_CALL    feof, C99, 3, 1
        PPE_CALL    ferror, C99, 4, 1
        PPE_CALL    fflush, C99, 5, 1
        PPE_CALL    fgetc, C99, 6, 1
        PPE_CALL    fgets, C99, 8, 3
        PPE_CALL    fileno, C99, 9, 1
        PPE_CALL    fopen, C99, 10, 2
        PPE_CALL    fputc, C99, 11, 2
        PPE_CALL    fputs, C99, 12, 2
        PPE_CALL    fread, C99, 13, 4
        PPE_CALL    fseek, C99, 15, 3
        PPE_CALL    ftell, C99, 17, 1
        PPE_CALL    fwrite, C99, 18, 4
        PPE_CALL    getc, C99, 19, 1
        PPE_CALL    getchar, C99, 20, 0
        PPE_CALL    putc, C99, 23, 2
        PPE_CALL    putchar, C99, 24, 1
        PPE_CALL    puts, C99, 25, 1
        PPE_CALL    remove, C99, 26, 1
        PPE_CALL    rename, C99, 27, 2
        PPE_CALL    rewind, C99, 28, 1
        PPE_CALL    setbuf, C99, 29, 2
        PPE_CALL    setvbuf, C99, 30, 4
        PPE_CALL    ungetc, C99, 34, 2
        PPE_VACALL  fprintf, 35, 2
        PPE_VACALL  printf, 37, 1
        PPE_VACALL  snprintf, 39, 3
        PPE_VACALL  sprintf, 40, 2
        PPE_VCALL   vfprintf, 35, 2
        PPE_VCALL   vprintf, 37, 1
        PPE_VCALL   vsnprintf, 39, 3
        PPE_VCALL   vsprintf, 40, 2
        PPE_VACALL  fscanf, 36, 2
        PPE_VACALL  scanf, 38, 1
        PPE_VACALL  sscanf, 41, 2
        PPE_VCALL   vfscanf, 36, 2
        PPE_VCALL   vscanf, 38, 1
        PPE_VCALL   vsscanf, 41, 2

        # POSIX.1 (libspe2's SPE_POSIX1_* opcodes; flags and errno values are Linux's)
        PPE_CALL    close, POSIX1, 2, 1
        PPE_CALL    creat, POSIX1, 3, 2
        PPE_CALL    fstat, POSIX1, 4, 2
        PPE_CALL    gettimeofday, POSIX1, 7, 2
        PPE_CALL    lseek, POSIX1, 9, 3
        PPE_CALL    lstat, POSIX1, 10, 2
        PPE_CALL    open, POSIX1, 15, 3
        PPE_CALL    read, POSIX1, 16, 3
        PPE_CALL    stat, POSIX1, 23, 2
        PPE_CALL    unlink, POSIX1, 24, 1
        PPE_CALL    write, POSIX1, 27, 3
        PPE_CALL    ftruncate, POSIX1, 28, 2
        PPE_CALL    access, POSIX1, 29, 2
        PPE_CALL    dup, POSIX1, 30, 1
        PPE_CALL    time, POSIX1, 31, 1
        PPE_CALL    dup2, POSIX1, 50, 2

# perror(s): the PPE prints errno's text, so errno goes along as the second argument.
        .text
        .global perror
        .type   perror, @function
perror:
        ila     $4, errno
        lqd     $4, 0($4)
        br      __perror
        .size   perror, .-perror
        PPE_CALL    __perror, C99, 22, 2
