#!/usr/bin/env python3
"""Writes trajectories/trunnion_bc_5axis.ngc: the five-axis example for machines/trunnion-bc.toml.

Axis positions from the nominal chain w C B X Y b Z t (docs/file-formats.md): the table turns by
-C about the C line and -B about the B line, the slides move the tool by +q, so the linear axes
that put the tool tip at p (workpiece frame) are q = R_B(-B) R_C(-C) (datum + p) - T, each rotation
about its line. Run: python3 trajectories/generate_5axis_bc.py > trajectories/trunnion_bc_5axis.ngc
"""
import math
datum=(150.0,0.0,-350.0); pC=(0,0,-450.0); pB=(0,0,-500.0); T=(0,0,-150.0)
def rz(p,phi):
    c,s=math.cos(phi),math.sin(phi); return (p[0]*c-p[1]*s, p[0]*s+p[1]*c, p[2])
def ry(p,phi):
    c,s=math.cos(phi),math.sin(phi); return (p[0]*c+p[2]*s, p[1], -p[0]*s+p[2]*c)
def sub(a,b): return tuple(x-y for x,y in zip(a,b))
def add(a,b): return tuple(x+y for x,y in zip(a,b))
def q_of(pw,A,C):
    p=add(datum,pw)
    p=add(rz(sub(p,pC),math.radians(-C)),pC)
    p=add(ry(sub(p,pB),math.radians(-A)),pB)
    return sub(p,T)
def rot_n(n,A,C): return ry(rz(n,math.radians(-C)),math.radians(-A))
# block: centre on C axis: x_w=-150, y_w=0; from table z_w=-100 to -40; half 40
cx,cy=-150.0,0.0; z0,z1=-100.0,-40.0; h=40.0
faces={'+x':((1,0,0)),'-x':((-1,0,0)),'+y':((0,1,0)),'-y':((0,-1,0))}
lines=[]
out=lambda s: lines.append(s)
out("( Five-axis example on the trunnion machine trunnion-bc: 3+2 faces and a simultaneous B/C move. )")
out("( X Y Z are the linear axes' positions, B C the rotary angles in degrees: no tool-centre-point )")
out("( control. A block 80 x 80 x 60 mm stands on the table centred on the C axis; at B-30 and C 0, 90, )")
out("( 180, 270 the tool traces a rectangle on the side face tilted towards the spindle, dwelling )")
out("( 0.5 s at each corner and edge middle, the measurement points; then B and C turn together. )")
out("G21 G90 G94")
out("G0 Z0")
def fmt(q,A,C): return "X%.3f Y%.3f Z%.3f B%.3f C%.3f"%(q[0],q[1],q[2],A,C)
A=-30.0  # the B tilt
for C in (0.0,90.0,180.0,270.0):
    best=max(faces.items(), key=lambda kv: rot_n(kv[1],A,C)[2])
    name,n=best
    # rectangle on face: along the face's in-plane horizontal direction t and vertical z
    t=(-n[1],n[0],0)
    fc=(cx+n[0]*h, cy+n[1]*h)
    pts=[]
    for (u,z) in [(-30,z0+10),(0,z0+10),(30,z0+10),(30,z1-10),(0,z1-10),(-30,z1-10),(-30,z0+10)]:
        pts.append((fc[0]+t[0]*u, fc[1]+t[1]*u, z))
    out("( C%g: face %s of the block )"%(C,name))
    # approach: 30 mm off the face along its normal
    app=(pts[0][0]+n[0]*30, pts[0][1]+n[1]*30, pts[0][2])
    out("G0 Z0"); out("G0 B%.3f C%.3f"%(A,C))
    q=q_of(app,A,C); out("G0 X%.3f Y%.3f"%(q[0],q[1])); out("G0 Z%.3f"%q[2])
    out("G1 "+fmt(q_of(pts[0],A,C),A,C)+" F1500")
    out("G4 P0.5")
    for p in pts[1:]:
        out("G1 "+fmt(q_of(p,A,C),A,C)); out("G4 P0.5")
    q=q_of(app,A,C); out("G1 X%.3f Y%.3f Z%.3f"%q)
# simultaneous: tool on top face centre point, A -30->0 and C 270->360 in one move, the tool tip following the same workpiece point
out("( Simultaneous B/C: from B-30 C270 to B0 C360 in one G1, the axes chosen so that the tool tip ends )")
out("( over the middle of the block top face. )")
top=(cx,cy,z1)
above=(cx,cy,z1+20)
out("G0 Z0")
q=q_of(above,-30,270); out("G0 X%.3f Y%.3f"%(q[0],q[1])); out("G0 Z%.3f"%q[2]); out("G4 P0.5")
q=q_of(above,0,360); out("G1 "+fmt(q,0,360)+" F2000"); out("G4 P0.5")
q=q_of(top,0,360); out("G1 "+fmt(q,0,360)); out("G4 P0.5")
out("G0 Z0")
out("G0 B0 C0")
out("M2")
print("\n".join(lines))
