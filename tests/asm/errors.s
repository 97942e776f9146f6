# Every error and warning of one run, each with its line and column.
	il	$3, 70000		# error: 2:9: out of range
	frob	$1			# error: 3:2: unknown instruction
	ai	$3, $3			# error: 4:5: operand
	lqd	$3, 5($1)		# warning: 5:10: multiple of 16
	andbi	$3, $4, 300		# warning: 6:16: out of range
	br	nowhere			# error: 7:5: undefined symbol
