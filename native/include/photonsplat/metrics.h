// Image metrics: how far an image is from a reference. Two families:
//
//   On the DISPLAY image (what a viewer sees): PSNR and SSIM on the luma of the display-encoded image:
//     each channel linear → clamp to [0, 1] → sRGB transfer curve (IEC 61966-2-1), then
//     Y' = 0.2126 R' + 0.7152 G' + 0.0722 B'  (Rec. 709 weights applied to the ENCODED values, i.e. luma, the
//     way most SSIM/PSNR figures of rendering papers are computed on 8-bit display images; where the weights
//     go is our documented choice, docs/reference.md). Data range 1.
//   On LINEAR radiance (what the renderer computes): RMSE and relative MSE over all pixels and the 3 channels.
//
// SSIM follows Wang et al. 2004 with an 11×11 Gaussian window (σ = 1.5, truncated at 3.5 σ: radius 5),
// K1 = 0.01, K2 = 0.03, population (not sample) covariances. As scikit-image does with gaussian_weights=True,
// the SSIM map is averaged only over the pixels whose whole window lies inside the image, i.e. a border of
// (11 − 1)/2 = 5 pixels is left out; images must therefore be at least 11×11. On those pixels the result equals
// skimage.metrics.structural_similarity(..., gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
// data_range=1) (tests/python/test_metrics.py checks 1e-3; in practice ~1e-7).
//
// Inputs are height × width × channels floats (channels 3 or 4: alpha is ignored), row-major. Non-finite values
// are refused (InvalidInput naming "image" or "reference"): a NaN would silently poison every figure.
#pragma once
#include <vector>

namespace ps {

struct ImageView {
    const float* pixels = nullptr;  // height × width × channels
    int width = 0, height = 0, channels = 0;
};

// relMSE = mean over pixels and channels of (a − b)² / (b² + ε), with b the reference: ε keeps dark pixels
// from dominating (the usual choice of denoising papers).
constexpr double kRelMseEpsilon = 1e-2;

// SSIM window: 11 taps, σ = 1.5 (Wang et al. 2004).
constexpr int kSsimRadius = 5;
constexpr double kSsimSigma = 1.5;

// Display luma Y' per pixel (see above), height × width, row-major.
std::vector<double> display_luma(const ImageView& image, const char* field = "image");

// PSNR in dB of the display luma, peak 1: 10 log10(1 / MSE). Identical images give +infinity (as scikit-image
// does): callers that need a finite number must cap it themselves.
double psnr(const ImageView& image, const ImageView& reference);
// Mean SSIM of the display luma, in [−1, 1]; 1 for identical images. Throws InvalidInput below 11×11.
double ssim(const ImageView& image, const ImageView& reference);
// sqrt(mean (a − b)²) on linear radiance, over pixels and the 3 colour channels.
double rmse(const ImageView& image, const ImageView& reference);
// mean (a − b)² / (b² + kRelMseEpsilon) on linear radiance, b = reference.
double relmse(const ImageView& image, const ImageView& reference);

}  // namespace ps
