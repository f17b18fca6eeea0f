"""The denoiser network's input features and output transform, in numpy: the same as
render/denoise_network.cpp (DenoiseWithNetwork; render/denoise.h lists them). The two must change
together."""
import numpy as np

ALBEDO_FLOOR = 0.01
MAX_RATIO = 1e4
CHANNELS = 12


def luma(x):
    return 0.2126 * x[..., 0] + 0.7152 * x[..., 1] + 0.0722 * x[..., 2]


def upper_median(values):
    if values.size == 0:
        return 1.0
    k = values.size // 2
    return float(np.partition(values, k)[k])


def features(radiance, albedo, normal, depth, variance):
    """(12, H, W) float32 features and (scale, albedo floor-clamped (H, W, 3)) to undo them."""
    radiance = np.nan_to_num(radiance.astype(np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    hit = depth > 0
    a = np.where(hit[..., None], np.maximum(ALBEDO_FLOOR, albedo.astype(np.float32)), 1.0)
    light = np.where(hit[..., None], np.maximum(0.0, radiance) / a, 0.0).astype(np.float32)
    scale = max(1e-6, upper_median(luma(light)[hit].astype(np.float32)))
    z_median = upper_median(depth[hit].astype(np.float32))
    x = np.zeros((CHANNELS,) + depth.shape, np.float32)
    x[0:3] = np.log1p(np.minimum(MAX_RATIO, light / scale)).transpose(2, 0, 1)
    x[3:6] = np.clip(albedo, 0.0, 1.0).transpose(2, 0, 1)
    x[6:9] = normal.transpose(2, 0, 1)
    x[9] = np.log(np.where(hit, depth, 1.0) / z_median)
    raw, demodulated = luma(radiance), luma(light)
    gain = np.where(raw > 1e-12, demodulated / np.maximum(raw, 1e-12), 1.0 / luma(a))
    var = np.nan_to_num(variance.astype(np.float32), nan=0.0, posinf=6e4)
    x[10] = np.log1p(np.minimum(MAX_RATIO, np.sqrt(np.maximum(var, 0.0)) * gain / scale))
    x[11] = 1.0
    x[:, ~hit] = 0.0
    return x, scale, a


def light_channels(y, x):
    """log(1 + L / s) (3, H, W) of the network's output y (4, H, W) for features x: its own
    estimate, blended (in L) with the input's by the weight sigmoid(y[3])."""
    own = np.expm1(np.clip(y[0:3], 0.0, np.log1p(MAX_RATIO)))
    alpha = 1.0 / (1.0 + np.exp(-y[3:4]))
    return np.log1p(alpha * own + (1.0 - alpha) * np.expm1(x[0:3]))


def radiance_from(y, scale, a, radiance, depth):
    """The denoised radiance (H, W, 3) from the network's output y (3, H, W)."""
    t = np.clip(y.transpose(1, 2, 0), 0.0, np.log1p(MAX_RATIO))
    out = np.expm1(t) * scale * a
    return np.where((depth > 0)[..., None], out, radiance)
