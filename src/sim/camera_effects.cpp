#include "sim/camera_effects.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

namespace idyvins::sim {

RealismOptions realismPreset(const std::string& name) {
  RealismOptions o;
  o.preset = name;
  if (name == "none") return o;
  if (name == "euroc") {
    // The parameters were set by measuring the real EuRoC V1_01 excerpt against the
    // simulated city scene with `idyvins imstats` (README: image statistics side by side).
    o.enabled = true;
    o.vignetting_k1 = -0.35;
    o.vignetting_k2 = 0.05;
    o.gain[0] = 1.0;
    o.gain[1] = 0.9;  // EuRoC's right camera: about 10 % darker
    o.offset[1] = 0.0;
    o.exposure_time_s = 0.006;
    o.blur_samples = 3;
    o.defocus_sigma_px = 1.2;
    o.auto_exposure = true;
    o.ae_target = 145;
    o.ae_rate = 0.3;
    o.full_well = 6000;
    o.read_noise = 1.5;
    o.low_texture_fraction = 0.5;
    o.low_texture_contrast = 0.25;
    o.plain_ground = true;
    return o;
  }
  throw std::invalid_argument("unknown realism preset '" + name + "' (none | euroc)");
}

void removeRealismEffects(RealismOptions& o, const std::string& effects) {
  std::stringstream list(effects);
  for (std::string e; std::getline(list, e, ',');) {
    if (e == "vignetting") {
      o.vignetting_k1 = o.vignetting_k2 = 0;
    } else if (e == "gain") {
      o.gain[1] = o.gain[0];
      o.offset[1] = o.offset[0];
    } else if (e == "blur") {
      o.exposure_time_s = 0;
      o.blur_samples = 1;
    } else if (e == "defocus") {
      o.defocus_sigma_px = 0;
    } else if (e == "exposure") {
      o.auto_exposure = false;
    } else if (e == "noise") {
      o.full_well = 0;
      o.read_noise = 0;
    } else if (e == "plain") {
      o.low_texture_fraction = 0;
      o.plain_ground = false;
    } else {
      throw std::invalid_argument("unknown realism effect '" + e +
                                  "' (vignetting, gain, blur, defocus, exposure, noise, plain)");
    }
  }
  if (!effects.empty()) o.preset += "-without-" + effects;
}

cv::Mat vignettingProfile(int width, int height, double cx, double cy, double k1, double k2) {
  cv::Mat v(height, width, CV_32F);
  const double half_diag2 = 0.25 * (static_cast<double>(width) * width + static_cast<double>(height) * height);
  for (int y = 0; y < height; ++y) {
    float* row = v.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / half_diag2;
      row[x] = static_cast<float>(1.0 + k1 * r2 + k2 * r2 * r2);
    }
  }
  return v;
}

double autoExposureStep(double exposure, double measured_mean, const RealismOptions& o) {
  if (measured_mean <= 1e-6) return std::min(o.ae_max, exposure * 2.0);
  const double next = exposure * std::pow(o.ae_target / measured_mean, o.ae_rate);
  return std::clamp(next, o.ae_min, o.ae_max);
}

std::vector<double> autoExposureSequence(const std::vector<double>& meter, const RealismOptions& o) {
  std::vector<double> e(meter.size(), 1.0);
  if (!o.auto_exposure || meter.empty()) return e;
  e[0] = std::clamp(meter[0] > 1e-6 ? o.ae_target / meter[0] : o.ae_max, o.ae_min, o.ae_max);
  for (std::size_t k = 1; k < meter.size(); ++k) e[k] = autoExposureStep(e[k - 1], meter[k - 1] * e[k - 1], o);
  return e;
}

cv::Mat applySensor(const cv::Mat& radiance, const cv::Mat& vignetting, double exposure, int cam,
                    const RealismOptions& o, std::uint64_t seed) {
  CV_Assert(radiance.type() == CV_32F && (cam == 0 || cam == 1));
  cv::Mat x = radiance.clone();
  if (o.defocus_sigma_px > 0) cv::GaussianBlur(x, x, cv::Size(0, 0), o.defocus_sigma_px, o.defocus_sigma_px);
  if (!vignetting.empty()) cv::multiply(x, vignetting, x);
  x.convertTo(x, CV_32F, exposure * o.gain[cam], o.offset[cam]);
  cv::Mat out(x.size(), CV_8UC1);
  cv::Mat noise(x.size(), CV_32F, cv::Scalar(0));
  const bool noisy = o.full_well > 0 || o.read_noise > 0;
  if (noisy) {
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  }
  const double shot = o.full_well > 0 ? 255.0 / o.full_well : 0.0, read2 = o.read_noise * o.read_noise;
  for (int y = 0; y < x.rows; ++y) {
    const float* in = x.ptr<float>(y);
    const float* nz = noise.ptr<float>(y);
    std::uint8_t* px = out.ptr<std::uint8_t>(y);
    for (int c = 0; c < x.cols; ++c) {
      const double v = in[c];
      const double sigma = noisy ? std::sqrt(std::max(0.0, v) * shot + read2) : 0.0;
      px[c] = cv::saturate_cast<std::uint8_t>(v + sigma * nz[c]);
    }
  }
  return out;
}

}  // namespace idyvins::sim
