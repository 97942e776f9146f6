# .irp, .irpc, .rept and the conditionals.
	.irp	r, 3, 4, 5
	il	$\r, 1		# => 40800083 40800084 40800085
	.endr
	.irpc	c, 123
	il	$3, \c		# => 40800083 40800103 40800183
	.endr
	.rept	3
	lnop			# => 00200000 00200000 00200000
	.endr
	.set	x, 2
	.if	x > 1
	il	$3, 8		# => 40800403
	.else
	il	$3, 9
	.endif
	.ifdef	x
	il	$3, 1		# => 40800083
	.endif
	.ifndef	nosuch
	il	$3, 2		# => 40800103
	.endif
	.if	x == 3
	il	$3, 3
	.elseif	x == 2
	il	$3, 4		# => 40800203
	.else
	il	$3, 5
	.endif
	.ifeq	x - 2
	nop			# => 40200000
	.endif
