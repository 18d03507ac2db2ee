#include "pipeline/run.h"

#include "config/modes.h"
#include "core/checksum.h"
#include "core/error.h"
#include "io/prefetch.h"

namespace idyvins::pipeline {

namespace {

/// `text` with each {name} replaced by spell(name).
std::string spelled(const std::string& text, const std::function<std::string(const std::string&)>& spell) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const std::size_t end = text[i] == '{' ? text.find('}', i) : std::string::npos;
    if (end == std::string::npos) {
      out += text[i];
      continue;
    }
    out += spell(text.substr(i + 1, end - i - 1));
    i = end;
  }
  return out;
}

}  // namespace

OptionError::OptionError(std::string option, std::string message)
    : std::invalid_argument(spelled(message, [](const std::string& name) { return name; })),
      option_(std::move(option)),
      message_(std::move(message)) {}

std::string OptionError::text(const std::function<std::string(const std::string&)>& spell) const {
  return spelled(message_, spell);
}

RunOptions applyRunRequest(const RunRequest& r, Config& config) {
  if (r.threads != 1 && r.threads != 2)
    throw OptionError("threads", "must be 1 or 2, got " + std::to_string(r.threads));
  if (r.localization_only && !r.load_map)
    throw OptionError("localization_only", "needs {load_map} DIR (the map to localize in)");
  if (r.localization_only && r.save_map)
    throw OptionError("save_map", "cannot go with {localization_only}: the map stays as loaded, nothing to save");
  if (!r.mode.empty() && !parseMode(r.mode, config.mode))
    throw OptionError("mode", "must be one of " + modeNames() + ", got '" + r.mode + "'");
  if (traitsOf(config.mode).needs_masks && !r.masks_available)
    throw OptionError(
        "mode", std::string(toString(config.mode)) + " needs ground-truth masks, which a live source does not have");
  if (r.solver_time_limit) config.estimator.time_limited = true;
  if (r.save_map || r.load_map) config.loop.enabled = true;  // the map is the loop closer's database
  RunOptions run;
  run.pipelined = r.threads == 2;
  run.feedback_delay = r.feedback_delay >= 0 ? r.feedback_delay : (run.pipelined ? 1 : 0);
  if (run.pipelined && run.feedback_delay != 1)
    throw OptionError("feedback_delay", "must be 1 with {threads} 2 (a pipelined run)");
  return run;
}

io::DatasetRequest datasetRequest(const Config& config, const std::string& groundtruth_topic, bool masks) {
  io::DatasetRequest r;
  r.topics.imu = config.imu_topic;
  r.topics.image0 = config.image0_topic;
  r.topics.image1 = config.num_cam == 2 ? config.image1_topic : "";
  r.topics.groundtruth = groundtruth_topic.empty() ? config.groundtruth_topic : groundtruth_topic;
  r.topics.segmentation = config.segmentation_topic;
  r.image_width = config.image_width;
  r.image_height = config.image_height;
  r.rig = {config.num_cam, config.use_imu, config.imu.noise.g_norm};
  r.masks = masks && !config.cam0_right;  // cam0's masks are the right image's when cam0 is the right camera
  r.segmentation_rgb_ids = config.segmentation_rgb_ids;
  r.segmentation_vehicle_ids = config.segmentation_vehicle_ids;
  return r;
}

io::OpenedDataset openDataset(const std::string& path, const Config& config, const std::string& groundtruth_topic,
                              bool masks) {
  checkMaskCamera(config);
  io::OpenedDataset in = io::openDataset(path, datasetRequest(config, groundtruth_topic, masks));
  if (traitsOf(config.mode).needs_masks && !in.has_masks)
    throw InputError(in.root, in.is_bag ? "mode seg needs ground-truth masks: a segmentation_topic in the config "
                                          "(VIODE: /cam0/segmentation)"
                                        : "mode seg needs mav0/cam0/mask/ (ground-truth masks)");
  return in;
}

std::string configChecksum(const Config& config) {
  std::uint64_t h = fnv1a64File(config.path);
  for (const std::string& cam : config.cam_paths) h = fnv1a64File(cam, h);
  return hex64(h);
}

std::size_t feed(io::DataSource& source, System& system, std::size_t max_frames, const std::atomic<int>* stop) {
  io::PrefetchSource prefetch(source, 4);
  std::size_t frames = 0;
  while (frames < max_frames && (stop == nullptr || *stop == 0)) {
    auto m = prefetch.next();
    if (!m) break;
    if (const auto* imu = std::get_if<ImuSample>(&*m)) {
      system.addImu(*imu);
      continue;
    }
    system.addFrame(std::get<StereoFrame>(*m));
    ++frames;
  }
  return frames;
}

}  // namespace idyvins::pipeline
