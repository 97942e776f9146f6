# .include finds files beside the source.
	.include	"part.inc"
	il	$3, PART	# => 40800583
	ai	$4, $4, 1	# => 1c004204
