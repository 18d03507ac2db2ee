#pragma once
// What a real camera does to the scene radiance the renderer computes (`simulate
// --realism`): defocus, motion blur over the exposure time (rendered as sub-frames along
// the true trajectory, see Scene), vignetting, per-camera gain and offset, auto-exposure
// following the scene's brightness, photon (shot) and read noise, 8-bit quantization.
// Pure functions on images; the Scene applies them per frame.

#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <string>
#include <vector>

namespace idyvins::sim {

struct RealismOptions {
  std::string preset = "none";  ///< none | euroc (see realismPreset)
  bool enabled = false;         ///< false: today's images exactly (Gaussian noise only)
  /// Vignetting V(r) = 1 + k1 r² + k2 r⁴, r = distance to the principal point over the half
  /// diagonal (0 centre, 1 corner).
  double vignetting_k1 = 0, vignetting_k2 = 0;
  double gain[2] = {1.0, 1.0};    ///< per camera (left, right)
  double offset[2] = {0.0, 0.0};  ///< gray levels added after the gain
  /// Exposure time for motion blur, s (0: no blur); blur_samples sub-frames evenly spread
  /// over [t − T/2, t + T/2] are averaged.
  double exposure_time_s = 0;
  int blur_samples = 1;
  double defocus_sigma_px = 0;  ///< Gaussian defocus, px (0: sharp)
  /// Auto-exposure: each frame's exposure factor moves the previous frame's mean brightness
  /// (metered on a quarter-resolution preview of cam0) toward ae_target by ae_rate (0..1)
  /// in log space, clamped to [ae_min, ae_max]. Off: factor 1.
  bool auto_exposure = false;
  double ae_target = 128, ae_rate = 0.3, ae_min = 0.25, ae_max = 4.0;
  /// Shot noise: full_well electrons at gray 255 (σ² = I·255/full_well); 0: none.
  double full_well = 0;
  double read_noise = 0;  ///< gray levels (σ), added to the shot noise
  /// Share of the static surfaces (walls, ground) given a plain material: their texture's
  /// contrast scaled by low_texture_contrast around its mean. Chosen per surface from the seed.
  double low_texture_fraction = 0;
  double low_texture_contrast = 0.15;
  /// The ground (floor, asphalt: static surfaces lying at z = 0 facing up) plain as well.
  bool plain_ground = false;
};

/// The named presets: "none" (disabled) and "euroc" (measured against the real EuRoC
/// excerpt, docs/real-images.md). Throws std::invalid_argument for another name.
RealismOptions realismPreset(const std::string& name);

/// The preset without some of its effects, for finding which one a result depends on: a
/// comma-separated list of vignetting, gain (the right camera's), blur, defocus, exposure
/// (auto-exposure), noise (shot and read) and plain (plain materials). The preset's name
/// records them ("euroc-without-blur,noise"). Throws std::invalid_argument for another name.
void removeRealismEffects(RealismOptions& options, const std::string& effects);

/// V(r) per pixel (CV_32F, width x height) for principal point (cx, cy).
cv::Mat vignettingProfile(int width, int height, double cx, double cy, double k1, double k2);

/// One auto-exposure step: the next exposure factor from the current one and the mean
/// brightness it produced.
double autoExposureStep(double exposure, double measured_mean, const RealismOptions& o);

/// The exposure factor of every frame from the metered mean radiance of each frame
/// (frame 0 starts converged: ae_target / meter[0], clamped).
std::vector<double> autoExposureSequence(const std::vector<double>& meter, const RealismOptions& o);

/// The sensor: radiance (CV_32F, gray levels at exposure 1) -> 8-bit image for camera
/// `cam` (0/1): defocus, vignetting (`vignetting` from vignettingProfile, or empty), ×
/// exposure × gain + offset, shot and read noise drawn from `seed`, rounding and clipping.
cv::Mat applySensor(const cv::Mat& radiance, const cv::Mat& vignetting, double exposure, int cam,
                    const RealismOptions& o, std::uint64_t seed);

}  // namespace idyvins::sim
