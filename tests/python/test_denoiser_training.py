"""tools/denoiser/train.py's network (the shipped denoiser's architecture and its smaller
variants, docs/rendering.md "The denoiser network")."""
import pathlib
import sys

import pytest

torch = pytest.importorskip("torch")
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "tools" / "denoiser"))
import features  # noqa: E402
import train  # noqa: E402


def weights(net):
    return sum(p.numel() for p in net.parameters())


@pytest.mark.parametrize("skips", ["concat", "add"])
def test_the_network_gives_four_channels_at_full_resolution(skips):
    # Any size that is a multiple of 8 (DenoiseWithNetwork pads to one): light and blend weight.
    net = train.Net((4, 8, 8), 4, skips).eval()
    with torch.no_grad():
        y = net(torch.zeros(1, features.CHANNELS, 16, 24))
    assert tuple(y.shape) == (1, 4, 16, 24)


def test_an_unknown_kind_of_skip_is_refused():
    with pytest.raises(ValueError, match="'sum' is neither 'concat' nor 'add'"):
        train.Net((4, 8, 8), 4, "sum")


def test_added_skips_save_the_decoders_input_weights():
    # A decoder level's 3 x 3 convolution reads 2 w channels concatenated or w added: w * w * 9
    # weights fewer at each of the two levels (widths 4 and 8 there), the rest unchanged.
    concat, add = train.Net((4, 8, 8), 4, "concat"), train.Net((4, 8, 8), 4, "add")
    assert weights(concat) - weights(add) == 9 * (4 * 4 + 8 * 8)
    # The shipped model's weights (render/models/denoiser.json: 155,652).
    assert weights(train.Net()) == 155652
