; realtime: 
; seed 308716653 (.ci/emu-random) without its zero-length G1 before the last G2
; the image traced a G2 the wrong way round when the preparation task was entered with SP at 4 mod 8 (CCR.STKALIGN was left clear: emu/tests/stack.rs); fixed by setting it in init
$11=0.012
$213=1
G21 G90 G17 G94
G1 F1500
G2 X0.4103 Y-1.4875 I-2.4935 J-1.4881
G4 P0.01
$12=0.008
G3 X1.2323 Y-4.6046 I-3.0662 J-2.4755
G3 X0.5419 Y-5.3970 R1.9646
G2 X6.3828 Y-4.6020 I2.8799 J0.6952
G0 X7.7739 Y-0.0402
G4 P0.01
$121=413.5
G2 X4.9996 Y-3.0915 I0.6418 J-3.3705
G3 X5.6565 Y-2.4087 I-1.9307 J2.5148
M5
