# .macro with positional and named arguments, defaults, \@ and .exitm.
	.macro	load reg, value=5
	il	\reg, \valudm
	.macro	twice a1
	ai	\a, \a, 1
	.endm
	.macro	counter
	il	$8, \@
	.endm
	.macro	upto n
	il	$6, \n
	.if	\n == 2
	.exitm
	.endif
	il	$4, \n
	.endm
start:	load	$3, 7		# => 40800383
	load	$3		# => 40800283
	load	value=2, reg=$3	# => 40800103
	twice	$5		# => 1c004285 1c004285
	counter			# => 40800204
	counter			# => 40800284
	upto	1		# e
	.endm
	.macro	twice a1
	ai	\a, \a, 1
	.endm
	.macro	counter
	il	$8, \@
	.endm
	.macro	upto n
	il	$6, \n
	.if	\n == 2
	.exitm
	.endif
	il	$4, \n
	.endm
start:	load	$3, 7		# => 40800383
	load	$3		# => 40800283
	load	value=2, reg=$3	# => 40800103
	twice	$5		# => 1c004285 1c004285
	counter			# => 40800204
	counter			# => 40800284
	upto	1		# => 40800086 40800087
	upto	2		# => 40800106
