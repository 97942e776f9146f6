# Every error and warning of one run, each with its line and column.
	il	$3, 70000		# error: 2:9: out of range
	frob	$1			# error: 3:2: Invalid mnemonic
	ai	$3, $3			# error: 4:5: Error in argument 3
	lqd	$3, 5($1)		# GNU as shifts the offset silently: no diagnostic
	andbi	$3, $4, 300		# warning: 6:16: out of range
	br	nowhere			# error: 7:5: undefined symbol
