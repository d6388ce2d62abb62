#!/usr/bin/env python3
"""Phase-1 trial deck of the blade-frame (conveyor) scene, hand-made outside the crate: static blade,
substrate moving at -v, heap topped up by insert/pack, deposit deleted downstream. Usage:
    python3 scripts/conveyor_trial.py --v 1.4 --blocks 60 --out DIR && (cd DIR && liggghts -in in.liggghts > out.txt)
    python3 scripts/conveyor_trial_blocks.py DIR/out.txt
heap topped up to a count by insert/pack, deposit deleted downstream and counted."""
import math, sys, os, argparse
p = argparse.ArgumentParser()
p.add_argument("--d", type=float, default=2.0)      # mm
p.add_argument("--gap", type=float, default=5.0)    # mm
p.add_argument("--v", type=float, default=1.4)
p.add_argument("--mu", type=float, default=0.2)
p.add_argument("--heap", type=float, default=10.0)  # heap height above the gap, in D
p.add_argument("--depth", type=float, default=6.0)  # in D
p.add_argument("--frac", type=float, default=0.33)  # Rayleigh fraction
p.add_argument("--block", type=float, default=5.0)  # block travel in D (one delete chunk)
p.add_argument("--blocks", type=int, default=40)
p.add_argument("--feed", type=str, default="count") # count | none
p.add_argument("--out", required=True)
a = p.parse_args()
D = a.d*1e-3; gap = a.gap*1e-3; v = a.v
rho, E, nu = 7980.0, 21e6, 0.3
G = E/(2*(1+nu)); tr = math.pi*(D/2)*math.sqrt(rho/G)/(0.1631*nu+0.8766)
dt = a.frac*tr
sp = D*1.0  # substrate spacing (touching)
ny = max(3, round(a.depth))
depth = ny*sp
H = gap + a.heap*D                    # heap height
Lh = H/math.tan(math.radians(30))     # heap base length at repose
heap_len = Lh + 3*D
behind = 16*D                         # room behind the blade: deposit runs 10 D, then deleted
xb = behind                           # blade rear face
xf = xb + D
Lx_raw = xf + heap_len + 2*D
nx = math.ceil(Lx_raw/sp); Lx = nx*sp
blade_top = 2*H + 2*D
zhi = blade_top + 2*D + v*v/9.81
ntarget = int(0.6*(0.5*H*Lh)*depth/(math.pi*D**3/6))
block_steps = math.ceil(a.block*D/v/dt)
os.makedirs(a.out, exist_ok=True)
with open(f"{a.out}/sub.data","w") as f:
    f.write(f"conveyor substrate\n\n{nx*ny} atoms\n3 atom types\n\n0 {Lx!r} xlo xhi\n0 {depth!r} ylo yhi\n{-D!r} {zhi!r} zlo zhi\n\nAtoms\n\n")
    i=0
    for ix in range(nx):
        for iy in range(ny):
            i+=1; f.write(f"{i} 3 {D} {rho} {(ix+0.5)*sp:.9e} {(iy+0.5)*sp:.9e} {-D/2:.9e}\n")
# blade box mesh
x0,x1,y0,y1,z0,z1 = xb, xb+D, 1e-6, depth-1e-6, gap, blade_top
V=[(x,y,z) for x in (x0,x1) for y in (y0,y1) for z in (z0,z1)]
idx=lambda i,j,k: i*4+j*2+k
quads=[(idx(0,0,0),idx(0,1,0),idx(0,1,1),idx(0,0,1)),(idx(1,0,0),idx(1,0,1),idx(1,1,1),idx(1,1,0)),
       (idx(0,0,0),idx(0,0,1),idx(1,0,1),idx(1,0,0)),(idx(0,1,0),idx(1,1,0),idx(1,1,1),idx(0,1,1)),
       (idx(0,0,0),idx(1,0,0),idx(1,1,0),idx(0,1,0)),(idx(0,0,1),idx(0,1,1),idx(1,1,1),idx(1,0,1))]
with open(f"{a.out}/blade.stl","w") as f:
    f.write("solid blade\n")
    for q in quads:
        for t in ((q[0],q[1],q[2]),(q[0],q[2],q[3])):
            f.write("  facet normal 0 0 0\n    outer loop\n")
            for k in t: f.write("      vertex %.9e %.9e %.9e\n"%V[k])
            f.write("    endloop\n  endfacet\n")
    f.write("endsolid blade\n")
ins_every = max(1, block_steps//5)
feed = "" if a.feed=="none" else f"""fix ins powder insert/pack seed 32452867 distributiontemplate pdd insert_every {ins_every} overlapcheck yes all_in yes vel constant 0 0 0 particles_in_region {ntarget} region heapreg"""
init = f"""fix ins0 powder insert/pack seed 15485867 distributiontemplate pdd insert_every once overlapcheck yes all_in yes vel constant 0 0 0 particles_in_region {ntarget} region fillreg
run 1
unfix ins0""" if a.feed=="none" else ""
mix = " ".join(["%s"]*9)
deck=f"""# conveyor: D={a.d}mm gap={a.gap}mm v={v} mu={a.mu} heap={a.heap}D depth={depth} target={ntarget} block={block_steps}
atom_style granular
atom_modify map array
boundary p p f
newton off
communicate single vel yes
units si
read_data sub.data
neighbor {0.5*D} bin
neigh_modify delay 0 exclude type 3 3
group powder type 1
group substrate type 3
fix m1 all property/global youngsModulus peratomtype {E} {E} {E}
fix m2 all property/global poissonsRatio peratomtype {nu} {nu} {nu}
fix m3 all property/global coefficientRestitution peratomtypepair 3 {' '.join(['0.5']*9)}
fix m4 all property/global coefficientFriction peratomtypepair 3 {' '.join([str(a.mu)]*9)}
fix m5 all property/global coefficientRollingFriction peratomtypepair 3 {' '.join(['0.1']*9)}
pair_style gran model hertz tangential history rolling_friction epsd2
pair_coeff * *
timestep {dt!r}
fix gravity powder gravity 9.81 vector 0.0 0.0 -1.0
fix plate all wall/gran model hertz tangential history rolling_friction epsd2 primitive type 2 zplane {-D!r}
fix blade all mesh/surface file blade.stl type 2
fix bladewall all wall/gran model hertz tangential history rolling_friction epsd2 mesh n_meshes 1 meshes blade
fix pts all particletemplate/sphere 15485863 atom_type 1 density constant {rho} radius constant {D/2!r}
fix pdd all particledistribution/discrete 32452843 1 pts 1.0
region heapreg block {xf!r} {xf+heap_len!r} 0 {depth!r} 0 {1.6*H!r} units box
region transreg block {xb-10*D!r} {xb!r} 0 {depth!r} {-0.2*D!r} {zhi!r} units box
fix front all wall/gran model hertz tangential history rolling_friction epsd2 primitive type 2 xplane {xf+heap_len!r}
region fillreg block {xf!r} {xf+heap_len!r} 0 {depth!r} 0 {2*H!r} units box
region delreg block 0 {xb-10*D!r} 0 {depth!r} {-0.2*D!r} {zhi!r} units box
region frontreg block {xf!r} {xf+6*D!r} 0 {depth!r} {gap!r} {zhi!r} units box
fix integrate powder nve/sphere
fix conv substrate move linear {-v!r} 0 0
{feed}
compute kepowder powder ke
thermo_style custom step atoms ke c_kepowder
thermo 1000
thermo_modify lost error norm no flush yes
variable mdel equal mass(powder,delreg)
variable nheap equal count(powder,heapreg)
variable mtrans equal mass(powder,transreg)
variable npow equal count(powder)
variable stepnow equal step
{init}
variable blk loop {a.blocks}
label loop
run {block_steps}
print "BLOCK ${{blk}} step ${{stepnow}} del ${{mdel}} heap ${{nheap}} powder ${{npow}} trans ${{mtrans}}"
delete_atoms region delreg
next blk
jump SELF loop
"""
open(f"{a.out}/in.liggghts","w").write(deck)
print(f"dt={dt:.3e} ntarget={ntarget} block_steps={block_steps} Lx={Lx:.4f} subst={nx*ny}")
