# How much of a simulated capture's held-out PSNR is the reference's own noise (docs/benchmarks.md, issue 25).
# The handheld captures are rendered at 4 samples per pixel and encoded as H.264 (scripts/make_handheld_capture.py):
# their frames carry noise no model can predict. Given clean renders of some held-out frames (the same script with
# --only FRAMES --samples 256 --masks 0 into CLEAN_DIR), this prints, inside the object's mask, per frame and as a
# mean, at full size and downscaled by 3 (box):
#   frame vs clean      the video frame against the clean render: the best PSNR a noise-free model can score
#   model vs frame      the object model composited over the video frame (eval's "over the photo"), against it
#   model vs clean      the same model composited over the clean render, against the clean render
#   object vs clean     inside the mask eroded by 2 px, the model's own colour (its render over white
#                       unpremultiplied by its alpha) against the clean render: compositing over the frame or
#                       the clean render fills whatever the model leaves transparent with the truth, which
#                       flatters a model whose object is partly transparent; this does not
# and the mean alpha there, and, if CAPTURE_DIR/render holds the 4-sample renders before encoding, their PSNR
# against the clean ones. Last, how sharp the model is: the Gaussian blur (sigma in full-size pixels, of
# BLUR_SIGMAS) of the clean render that the model over it matches best inside the eroded mask, and the PSNR there
# (the same search for the video frame says whether the frames are softer than the clean render).
#   python3 bench/capture_noise_ceiling.py CAPTURE_DIR WORK_DIR CLEAN_DIR EVAL_DIR
# CAPTURE_DIR: the script's OUT_DIR (masks/, render/); WORK_DIR: `nerfpt capture`'s output (frames/, the decoded
# video); EVAL_DIR: `nerfpt eval MODEL WORK_DIR --split test -o EVAL_DIR --alpha` (NAME.png over white, NAME_alpha.png).
import os, sys
import cv2
import numpy as np

if len(sys.argv) != 5:
    sys.exit('usage: capture_noise_ceiling.py CAPTURE_DIR WORK_DIR CLEAN_DIR EVAL_DIR')
capture, work, clean_dir, eval_dir = sys.argv[1:]


def read(path, grey=False):
    im = cv2.imread(path, cv2.IMREAD_UNCHANGED)
    if im is None:
        sys.exit(f'capture_noise_ceiling: cannot read {path}')
    im = im.astype(np.float64) / (65535.0 if im.dtype == np.uint16 else 255.0)
    if grey:
        if im.ndim == 3:  # alpha if there is one that is not opaque everywhere, else the mean of the colours
            im = im[..., 3] if im.shape[2] == 4 and im[..., 3].min() < 1 else im[..., :3].mean(-1)
        return im
    return im[..., 2::-1] if im.ndim == 3 else np.repeat(im[..., None], 3, -1)


def psnr(a, b, mask):
    return -10 * np.log10(np.mean((a - b)[mask] ** 2))


def shrink(x):
    h, w = x.shape[0] // 3, x.shape[1] // 3
    return cv2.resize(x[:3 * h, :3 * w], (w, h), interpolation=cv2.INTER_AREA)


# The held-out frames that have a clean render (eval renders only the held-out split).
names = sorted(n for n in os.listdir(os.path.join(clean_dir, 'render'))
               if n.endswith('.png') and os.path.exists(os.path.join(eval_dir, n)))
if not names:
    sys.exit(f'capture_noise_ceiling: no frame of {eval_dir} has a clean render in {clean_dir}/render')
raw_dir = os.path.join(capture, 'render')
cols = ['frame vs clean', 'model vs frame', 'model vs clean']
inner_kernel = np.ones((5, 5), np.uint8)
BLUR_SIGMAS = (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0)


def best_blur(image, blurred_cleans, mask):
    # (sigma, PSNR) of the blurred clean render (one per BLUR_SIGMAS) closest to image inside mask
    best = max((psnr(image, b, mask), s) for b, s in zip(blurred_cleans, BLUR_SIGMAS))
    return best[1], best[0]


rows = []
for n in names:
    clean = read(os.path.join(clean_dir, 'render', n))
    frame = read(os.path.join(work, 'frames', n))
    mask = read(os.path.join(capture, 'masks', n), grey=True) > 0.5
    render = read(os.path.join(eval_dir, n))
    alpha = read(os.path.join(eval_dir, n[:-4] + '_alpha.png'), grey=True)[..., None]
    premultiplied = render - (1 - alpha)  # eval renders over white
    over_frame, over_clean = premultiplied + (1 - alpha) * frame, premultiplied + (1 - alpha) * clean
    row = []
    for f in (lambda x: x, shrink):
        m = f(mask.astype(np.float64)) > 0.5
        row += [psnr(f(frame), f(clean), m), psnr(f(over_frame), f(frame), m), psnr(f(over_clean), f(clean), m)]
    inner = cv2.erode(mask.astype(np.uint8), inner_kernel) > 0
    own = premultiplied / np.maximum(alpha, 1e-3)
    row += [psnr(own, clean, inner), float(alpha[..., 0][inner].mean())]
    raw = os.path.join(raw_dir, n)
    row.append(psnr(read(raw), clean, mask) if os.path.exists(raw) else float('nan'))
    blurred = [clean if s == 0 else cv2.GaussianBlur(clean, (0, 0), s) for s in BLUR_SIGMAS]
    row += [*best_blur(over_clean, blurred, inner), best_blur(frame, blurred, inner)[0]]
    rows.append(row)

header = [c + ' (full)' for c in cols] + [c + ' (1/3)' for c in cols] + ['object vs clean (full, inside)',
                                                                         'alpha inside', '4-spp render vs clean (full)',
                                                                         'model blur sigma (px)', 'model vs blurred clean',
                                                                         'frame blur sigma (px)']
print('| frame | ' + ' | '.join(header) + ' |')
print('|---' * (len(header) + 1) + '|')
for n, r in zip(names, rows):
    print(f'| {n} | ' + ' | '.join(f'{x:.4f}' if h == 'alpha inside' else f'{x:.2f}' for h, x in zip(header, r)) + ' |')
print('| mean | ' + ' | '.join(f'{x:.4f}' if h == 'alpha inside' else f'{x:.2f}'
                             for h, x in zip(header, np.mean(rows, 0))) + ' |')
