; realtime: 
; S-curve ($210=1) with Z pen moves and $122 changed mid-job: 4.04 % longer on the image before the cosine ramp's Newton solve converged within f32 (issue 23)
$210=1
$111=1071
G21 G90 G17 G94
G1 F1500
M3
G1 X-1.2077 Y7.6439
G4 P0.01
$122=73.5
M5
G0 X-7.2378 Y1.5938
M3
G2 X-9.8674 Y-3.3572 R-3.5438
G1 X-2.5852 Y-8.3379
M5
G1 X-8.4888 Y-10.3753
M3
G1 X0 Y0
M5
