# Where the albedo AOV of a relightable model is wrong (docs/benchmarks.md, issue 24): test views 0, 5, 10 of the
# dev set against the ground truth, after score.py's per-channel scale: PSNR, the share of the error in the
# silhouette band, PSNR after blurring both (high- against low-frequency error), a per-channel affine fit in
# linear (pred = a truth + b), the error by the truth's brightness, and the PSNR after that affine correction.
#   python3 bench/relight_albedo_error.py PRED_DIR [ERROR_PNG]    (PRED_DIR/aov/albedo_{0,5,10}.exr; OpenImageIO, cv2)
# NERFPT_RELIGHT_DEV overrides ../shared/data/relight/dev.
import OpenImageIO as oiio, numpy as np, cv2, sys
def read(p):
    i=oiio.ImageInput.open(p); s=i.spec(); a=np.asarray(i.read_image(0,0,0,s.nchannels,'float'),np.float32).reshape(s.height,s.width,s.nchannels); i.close(); return a
def srgb(x):
    x=np.clip(x,0,1); return np.where(x<=0.0031308,12.92*x,1.055*np.power(x,1/2.4)-0.055)
def psnr(a,b): return -10*np.log10(np.mean((a-b)**2))
import os
d=os.path.join(os.environ.get('NERFPT_RELIGHT_DEV', os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..', 'shared', 'data', 'relight', 'dev')), 'test') + '/'
pred=sys.argv[1]; views=(0,5,10)
G=[];P=[];W=[]
for k in views:
    g=read(d+'albedo_%d.exr'%k); G.append(g[...,:3]/np.maximum(g[...,3:4],1e-6)); W.append(g[...,3]>0.5)
    P.append(read(pred+'/aov/albedo_%d.exr'%k)[...,:3])
G=np.stack(G);P=np.stack(P);W=np.stack(W)
s=np.array([(P[...,c][W]*G[...,c][W]).sum()/(P[...,c][W]**2).sum() for c in range(3)])
Ps=P*s
print('scale',np.round(s,3))
ps=[psnr(srgb(Ps[k])[W[k]],srgb(G[k])[W[k]]) for k in range(3)]
print('psnr per view',np.round(ps,2),'mean',round(np.mean(ps),2))
# band
band=[]; inner=[]
for k in range(3):
    m=W[k].astype(np.uint8); er=cv2.erode(m,np.ones((5,5),np.uint8))>0
    e=(srgb(Ps[k])-srgb(G[k]))**2
    inner.append(e[er].sum()); band.append(e[W[k]&~er].sum())
print('error share in 2px band: %.2f'%(sum(band)/(sum(band)+sum(inner))))
# blur
for sig in (1,2,4):
    pb=[];
    for k in range(3):
        m=W[k].astype(np.float32); er=cv2.erode(W[k].astype(np.uint8),np.ones((9,9),np.uint8))>0
        a=cv2.GaussianBlur(srgb(Ps[k])*m[...,None],(0,0),sig)/np.maximum(cv2.GaussianBlur(m,(0,0),sig),1e-6)[...,None]
        b=cv2.GaussianBlur(srgb(G[k])*m[...,None],(0,0),sig)/np.maximum(cv2.GaussianBlur(m,(0,0),sig),1e-6)[...,None]
        pb.append(psnr(a[er],b[er]))
    print('blur sigma %d: psnr (interior) %.2f'%(sig,np.mean(pb)))
# affine in linear
for c in range(3):
    x=G[...,c][W]; y=Ps[...,c][W]; A=np.vstack([x,np.ones_like(x)]).T; co=np.linalg.lstsq(A,y,rcond=None)[0]
    print('channel',c,'pred = %.3f truth + %.3f'%tuple(co))
# error by truth luminance bins (srgb)
lum=srgb(G).mean(-1)[W]; err=((srgb(Ps)-srgb(G))**2).mean(-1)[W]
for lo,hi in ((0,.3),(.3,.6),(.6,.8),(.8,1.01)):
    sel=(lum>=lo)&(lum<hi); print('truth srgb lum %.1f-%.1f: %.1f%% px, %.1f%% of err, rmse %.3f'%(lo,hi,100*sel.mean(),100*err[sel].sum()/err.sum(),np.sqrt(err[sel].mean())))
# error image
if len(sys.argv)>2:
    tiles=[]
    for k in range(3):
        e=np.abs(srgb(Ps[k])-srgb(G[k])).mean(-1)*W[k]
        row=np.concatenate([srgb(G[k])*W[k][...,None],srgb(Ps[k])*W[k][...,None],np.repeat(np.clip(e*4,0,1)[...,None],3,-1)],1)
        tiles.append(row)
    cv2.imwrite(sys.argv[2],(np.concatenate(tiles,0)*255).astype(np.uint8)[...,::-1])
# per-channel affine correction in linear, then PSNR
Pa=np.empty_like(Ps)
for c in range(3):
    x=P[...,c][W]; y=G[...,c][W]; A=np.vstack([x,np.ones_like(x)]).T; co=np.linalg.lstsq(A,y,rcond=None)[0]
    Pa[...,c]=P[...,c]*co[0]+co[1]
pa=[psnr(srgb(Pa[k])[W[k]],srgb(G[k])[W[k]]) for k in range(3)]
print('affine-corrected psnr %.2f'%np.mean(pa))
# The albedo against the true normal (docs/benchmarks.md, "the albedo against the normal"): the low-frequency
# ratio pred / truth (both blurred by 2 px inside the mask) by the normal's up component (world +z), and the PSNR
# once a smooth function of the normal (log ratio fitted over 1, x, y, z and the quadratic terms) is divided out:
# what a light whose vertical profile is right could give.
N=np.stack([read(d+'normal_%d.exr'%k)[...,:3] for k in views])
ratios=[]; ups=[]
for k in range(3):
    m=W[k].astype(np.float32); er=cv2.erode(W[k].astype(np.uint8),np.ones((7,7),np.uint8))>0
    bl=lambda x: cv2.GaussianBlur(x*m[...,None],(0,0),2)/np.maximum(cv2.GaussianBlur(m,(0,0),2),1e-6)[...,None]
    ratios.append((bl(Ps[k]).mean(-1)/np.maximum(bl(G[k]).mean(-1),1e-3))[er]); ups.append(N[k][...,2][er])
ratio=np.concatenate(ratios); up=np.concatenate(ups)
for lo in np.arange(-1,1,0.25):
    sel=(up>=lo)&(up<lo+0.25)
    if sel.sum()>50: print('normal z %+.2f..%+.2f: %6d px, albedo / truth (low frequency) %.3f'%(lo,lo+.25,sel.sum(),np.median(ratio[sel])))
nx,ny,nz=N[...,0][W],N[...,1][W],N[...,2][W]
X=np.stack([np.ones_like(nz),nx,ny,nz,nx*ny,nx*nz,ny*nz,nx*nx-ny*ny,3*nz*nz-1],-1)
Pn=P.copy()
for c in range(3):
    lr=np.log(np.maximum(P[...,c][W],1e-3))-np.log(np.maximum(G[...,c][W],1e-3))
    co=np.linalg.lstsq(X,lr,rcond=None)[0]
    v=Pn[...,c]; v[W]=v[W]/np.exp(X@co-co[0]); Pn[...,c]=v
sn=np.array([(Pn[...,c][W]*G[...,c][W]).sum()/(Pn[...,c][W]**2).sum() for c in range(3)])
print('psnr with the normal-dependent part divided out %.2f'%np.mean([psnr(srgb(Pn[k]*sn)[W[k]],srgb(G[k])[W[k]]) for k in range(3)]))
