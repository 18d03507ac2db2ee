#include "io/bag_dataset.h"

#include <algorithm>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "io/bag_file.h"
#include "io/png_gray.h"

namespace idyvins::io {

namespace {

using Kind = BagMessageKind;

/// "a (type), b (type)" of the topics whose kind is one of `wanted` (or "none").
std::string listTopics(const std::vector<BagTopicInfo>& topics, std::initializer_list<Kind> wanted) {
  std::string out;
  for (const BagTopicInfo& t : topics)
    if (std::find(wanted.begin(), wanted.end(), messageKind(t.type)) != wanted.end())
      out += (out.empty() ? "" : ", ") + t.topic + " (" + t.type + ")";
  return out.empty() ? "none" : out;
}

/// The kind of `topic`, checked against `allowed`; InputError naming what the bag has.
Kind checkTopic(const std::string& path, const std::vector<BagTopicInfo>& topics, const std::string& topic,
                const std::string& key, std::initializer_list<Kind> allowed) {
  const auto it = std::find_if(topics.begin(), topics.end(), [&](const BagTopicInfo& t) { return t.topic == topic; });
  if (it == topics.end())
    throw InputError(path, "topic '" + topic + "' (config key " + key + ") is not in the bag; its image topics: " +
                               listTopics(topics, {Kind::kImage, Kind::kCompressedImage}) +
                               "; its IMU topics: " + listTopics(topics, {Kind::kImu}));
  const Kind kind = messageKind(it->type);
  if (std::find(allowed.begin(), allowed.end(), kind) != allowed.end()) return kind;
  std::string names;
  for (Kind a : allowed) names += (names.empty() ? "" : " or ") + std::string(kindName(a));
  throw InputError(path, "topic '" + topic + "' has type " + it->type + ", expected " + names);
}

std::string where(const std::string& topic, std::size_t ordinal) {
  return "topic '" + topic + "' message " + std::to_string(ordinal);
}

/// Strictly increasing stamps per topic.
void checkIncreasing(const std::string& path, const std::string& topic, std::size_t ordinal, TimeNs prev, TimeNs t) {
  if (ordinal > 1 && t <= prev)
    throw InputError(path, where(topic, ordinal) + ": header stamp " + std::to_string(t) +
                               " ns is not after the previous one (" + std::to_string(prev) +
                               " ns); stamps must increase");
}

int channelsOf(const std::string& encoding) {
  if (encoding == "mono8") return 1;
  if (encoding == "rgb8" || encoding == "bgr8") return 3;
  if (encoding == "rgba8" || encoding == "bgra8") return 4;
  return 0;
}

void checkSize(const std::string& path, const std::string& topic, std::size_t ordinal, int width, int height,
               int expected_width, int expected_height) {
  if (expected_width > 0 && (width != expected_width || height != expected_height))
    throw InputError(path, where(topic, ordinal) + ": image is " + std::to_string(width) + "x" +
                               std::to_string(height) + ", the config says " + std::to_string(expected_width) + "x" +
                               std::to_string(expected_height));
}

bool supportedCompression(const std::string& format) {
  return format.find("png") != std::string::npos || format.find("jpeg") != std::string::npos ||
         format.find("jpg") != std::string::npos;
}

/// The encoding or compression check of an image message (no pixels decoded).
void checkImageFormat(const BagImage& m) {
  if (m.compressed && !supportedCompression(m.format))
    throw BagMessageError("unsupported compressed format '" + m.format + "' (supported: png, jpeg)");
  if (!m.compressed && channelsOf(m.encoding) == 0)
    throw BagMessageError("unsupported image encoding '" + m.encoding +
                          "' (supported: mono8, rgb8, bgr8, rgba8, bgra8)");
}

/// An uncompressed image wrapped (not copied) as CV_8UC(channels).
cv::Mat wrapped(const BagImage& m, int ch) {
  constexpr std::uint32_t kMaxSide = 1u << 16;  // beyond any camera; keeps OpenCV's int sizes exact
  if (m.width == 0 || m.height == 0 || m.width > kMaxSide || m.height > kMaxSide)
    throw BagMessageError("an image of " + std::to_string(m.width) + "x" + std::to_string(m.height) + " pixels");
  if (m.step < static_cast<std::uint64_t>(m.width) * static_cast<std::uint64_t>(ch) ||
      m.size < static_cast<std::size_t>(m.step) * m.height)
    throw BagMessageError("image data is shorter than height x step");
  return cv::Mat(static_cast<int>(m.height), static_cast<int>(m.width), CV_8UC(ch), const_cast<std::uint8_t*>(m.data),
                 m.step);
}

/// An image message as 8-bit gray (OpenCV's colour conversion, cv::imdecode for png and jpeg).
cv::Mat toGray(const BagImage& m) {
  checkImageFormat(m);
  cv::Mat gray;
  if (m.compressed) {
    std::string why;
    const GrayPng kind = decodeGrayPng(m.data, m.size, gray, why);
    if (kind == GrayPng::kCorrupt) throw BagMessageError("the " + m.format + " data is a corrupt PNG: " + why);
    if (kind == GrayPng::kDecoded) return gray;
    const cv::Mat decoded = cv::imdecode(cv::Mat(1, static_cast<int>(m.size), CV_8U, const_cast<std::uint8_t*>(m.data)),
                                         cv::IMREAD_UNCHANGED);
    if (decoded.empty() || decoded.depth() != CV_8U)
      throw BagMessageError("the " + m.format + " data does not decode to an 8-bit image");
    if (decoded.channels() == 1) return decoded;
    cv::cvtColor(decoded, gray, decoded.channels() == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
    return gray;
  }
  const int ch = channelsOf(m.encoding);
  const cv::Mat w = wrapped(m, ch);
  if (ch == 1) return w.clone();
  const int code = m.encoding == "rgb8"    ? cv::COLOR_RGB2GRAY
                   : m.encoding == "bgr8"  ? cv::COLOR_BGR2GRAY
                   : m.encoding == "rgba8" ? cv::COLOR_RGBA2GRAY
                                           : cv::COLOR_BGRA2GRAY;
  cv::cvtColor(w, gray, code);
  return gray;
}

/// A segmentation image as CV_8UC3 in RGB order.
cv::Mat toRgb(const BagImage& m) {
  cv::Mat rgb;
  if (m.compressed) {
    const cv::Mat bgr =
        cv::imdecode(cv::Mat(1, static_cast<int>(m.size), CV_8U, const_cast<std::uint8_t*>(m.data)), cv::IMREAD_COLOR);
    if (bgr.empty()) throw BagMessageError("the " + m.format + " data does not decode");
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
    return rgb;
  }
  const int ch = channelsOf(m.encoding);
  if (ch < 3)
    throw BagMessageError("segmentation encoding '" + m.encoding + "' is not a colour one (rgb8, bgr8, rgba8, bgra8)");
  const cv::Mat w = wrapped(m, ch);
  if (m.encoding == "rgb8") return w.clone();
  const int code = m.encoding == "bgr8"    ? cv::COLOR_BGR2RGB
                   : m.encoding == "rgba8" ? cv::COLOR_RGBA2RGB
                                           : cv::COLOR_BGRA2RGB;
  cv::cvtColor(w, rgb, code);
  return rgb;
}

GroundTruthState groundTruthOf(const BagPose& p) {
  GroundTruthState g;
  g.t_ns = p.stamp_ns;
  g.p_w_b = p.p;
  g.q_w_b = p.q;
  if (g.q_w_b.norm() < 1e-9) g.q_w_b = Eigen::Quaterniond::Identity();
  g.q_w_b.normalize();
  return g;
}

ImageRecord imageRecord(const std::string& path, const std::string& topic, std::size_t ordinal, TimeNs t) {
  ImageRecord r;
  r.t_ns = t;
  r.path = path + ":" + topic;
  r.csv_line = static_cast<int>(ordinal);
  r.exists = true;
  return r;
}

/// One role a topic plays in the index.
enum class Role { kImu, kCam0, kCam1, kGroundTruth, kSegmentation };

/// The index pass over one message of `role` (the `ordinal`-th on its topic).
void indexMessage(BagCursor& cursor, Role role, Kind kind, std::size_t ordinal, const std::string& path,
                  int expected_width, int expected_height, BagIndex& index) {
  EurocDataset& ds = index.dataset;
  const std::string& topic = cursor.topic();
  if (role == Role::kImu) {
    const ImuSample s = cursor.imu();
    checkIncreasing(path, topic, ordinal, ds.imu.empty() ? 0 : ds.imu.back().t_ns, s.t_ns);
    if (!s.gyr_b.allFinite() || !s.acc_b.allFinite())
      throw BagMessageError("non-finite angular velocity or acceleration");
    ds.imu.push_back(s);
  } else if (role == Role::kGroundTruth) {
    const GroundTruthState g = groundTruthOf(cursor.pose(kind));
    checkIncreasing(path, topic, ordinal, ds.groundtruth.empty() ? 0 : ds.groundtruth.back().t_ns, g.t_ns);
    if (!g.p_w_b.allFinite()) throw BagMessageError("non-finite position");
    ds.groundtruth.push_back(g);
  } else {
    const BagImage img = cursor.image(kind);
    std::vector<ImageRecord>& records = role == Role::kCam0   ? ds.cam0
                                        : role == Role::kCam1 ? ds.cam1
                                                              : index.segmentation;
    if (role != Role::kSegmentation) {
      checkImageFormat(img);
      if (!img.compressed)
        checkSize(path, topic, ordinal, static_cast<int>(img.width), static_cast<int>(img.height), expected_width,
                  expected_height);
    }
    checkIncreasing(path, topic, ordinal, records.empty() ? 0 : records.back().t_ns, img.stamp_ns);
    records.push_back(imageRecord(path, topic, ordinal, img.stamp_ns));
  }
}

/// Each frame's segmentation: the image with cam0's stamp (-1 = none).
void pairSegmentation(BagIndex& index, const EurocOptions& options) {
  const EurocDataset& ds = index.dataset;
  std::vector<StereoPair> seg_pairs;
  std::vector<std::size_t> u0, u1;
  pairByTime(ds.cam0, index.segmentation, options.pair_tolerance_ns, seg_pairs, u0, u1);
  std::map<std::size_t, long> seg_of_cam0;
  for (const auto& p : seg_pairs) seg_of_cam0[p.i0] = static_cast<long>(p.i1);
  for (const auto& p : ds.pairs) {
    const auto it = seg_of_cam0.find(p.i0);
    index.segmentation_of_pair.push_back(it == seg_of_cam0.end() ? -1 : it->second);
  }
}

}  // namespace

bool isBagFile(const std::string& path) { return bagFormat(path) != BagFormat::kNone; }

BagIndex indexBag(const std::string& path, const BagTopics& topics, int expected_width, int expected_height,
                  const EurocOptions& options) {
  std::unique_ptr<BagFile> bag = openBagFile(path);
  BagIndex index;
  index.path = path;
  index.topics = topics;
  index.all_topics = bag->topics();
  if (std::all_of(index.all_topics.begin(), index.all_topics.end(), [](const BagTopicInfo& t) { return t.count == 0; }))
    throw InputError(path, "the bag holds no messages");
  // The roles: topic -> (role, kind); the image and IMU topics are required.
  std::vector<std::pair<std::string, std::pair<Role, Kind>>> roles;
  const auto& all = index.all_topics;
  roles.push_back(
      {topics.image0,
       {Role::kCam0, checkTopic(path, all, topics.image0, "image0_topic", {Kind::kImage, Kind::kCompressedImage})}});
  roles.push_back({topics.imu, {Role::kImu, checkTopic(path, all, topics.imu, "imu_topic", {Kind::kImu})}});
  if (!topics.image1.empty())
    roles.push_back(
        {topics.image1,
         {Role::kCam1, checkTopic(path, all, topics.image1, "image1_topic", {Kind::kImage, Kind::kCompressedImage})}});
  if (!topics.groundtruth.empty())
    roles.push_back({topics.groundtruth,
                     {Role::kGroundTruth, checkTopic(path, all, topics.groundtruth, "groundtruth_topic",
                                                     {Kind::kOdometry, Kind::kTransform, Kind::kPose, Kind::kPoint})}});
  if (!topics.segmentation.empty())
    roles.push_back({topics.segmentation,
                     {Role::kSegmentation, checkTopic(path, all, topics.segmentation, "segmentation_topic",
                                                      {Kind::kImage, Kind::kCompressedImage})}});
  std::vector<std::string> names;
  for (const auto& r : roles) names.push_back(r.first);
  std::map<std::string, std::size_t> ordinal;
  std::unique_ptr<BagCursor> cursor = bag->read(names);
  while (cursor->next()) {
    const std::string& topic = cursor->topic();
    const std::size_t k = ++ordinal[topic];
    for (const auto& [name, role] : roles) {
      if (name != topic) continue;
      try {
        indexMessage(*cursor, role.first, role.second, k, path, expected_width, expected_height, index);
      } catch (const BagMessageError& e) {
        throw InputError(path, where(topic, k) + ": " + e.what());
      }
    }
  }
  index.format = bag->format();
  EurocDataset& ds = index.dataset;
  ds.root = path;
  ds.has_groundtruth = !ds.groundtruth.empty();
  if (ds.cam0.empty()) throw InputError(path, "topic '" + topics.image0 + "' holds no images");
  if (ds.imu.empty()) throw InputError(path, "topic '" + topics.imu + "' holds no IMU samples");
  if (ds.stereo()) {
    pairByTime(ds.cam0, ds.cam1, options.pair_tolerance_ns, ds.pairs, ds.unmatched0, ds.unmatched1);
  } else {
    for (std::size_t i = 0; i < ds.cam0.size(); ++i) ds.pairs.push_back({ds.cam0[i].t_ns, i, 0});
  }
  if (!index.segmentation.empty()) pairSegmentation(index, options);
  return index;
}

/// The open bag, a cursor over the image topics, and the decoded images waiting for their
/// partner (by position on their topic).
struct BagSource::Reader {
  std::unique_ptr<BagFile> bag;
  std::unique_ptr<BagCursor> cursor;
  Kind kind0 = Kind::kOther, kind1 = Kind::kOther, kind_seg = Kind::kOther;
  std::map<std::size_t, cv::Mat> left, right, seg;
  std::size_t seen0 = 0, seen1 = 0, seen_seg = 0;
  std::vector<bool> needed0, needed1, needed_seg;  ///< the messages that belong to a frame
};

BagSource::BagSource(BagIndex index, int expected_width, int expected_height, std::optional<SegmentationColors> masks)
    : index_(std::move(index)),
      masks_(std::move(masks)),
      width_(expected_width),
      height_(expected_height),
      reader_(std::make_unique<Reader>()) {
  if (masks_ && index_.segmentation.empty())
    throw InputError(index_.path, "masks were asked for but the bag has no segmentation topic (segmentation_topic)");
  Reader& r = *reader_;
  r.bag = openBagFile(index_.path);
  std::vector<std::string> topics{index_.topics.image0};
  if (index_.dataset.stereo()) topics.push_back(index_.topics.image1);
  if (masks_) topics.push_back(index_.topics.segmentation);
  r.cursor = r.bag->read(topics);
  for (const auto& t : index_.all_topics) {
    if (t.topic == index_.topics.image0) r.kind0 = messageKind(t.type);
    if (t.topic == index_.topics.image1) r.kind1 = messageKind(t.type);
    if (t.topic == index_.topics.segmentation) r.kind_seg = messageKind(t.type);
  }
  r.needed_seg.assign(index_.segmentation.size(), false);
  if (masks_)
    for (long k : index_.segmentation_of_pair)
      if (k >= 0) r.needed_seg[static_cast<std::size_t>(k)] = true;
  r.needed0.assign(index_.dataset.cam0.size(), false);
  r.needed1.assign(index_.dataset.cam1.size(), false);
  for (const auto& p : index_.dataset.pairs) {
    r.needed0[p.i0] = true;
    if (index_.dataset.stereo()) r.needed1[p.i1] = true;
  }
}

BagSource::~BagSource() = default;

void BagSource::takeMessage() {
  Reader& r = *reader_;
  const std::string& path = index_.path;
  const std::string& topic = r.cursor->topic();
  std::size_t k = 0;
  try {
    if (topic == index_.topics.image0) {
      k = r.seen0++;
      if (k < r.needed0.size() && r.needed0[k]) r.left[k] = toGray(r.cursor->image(r.kind0));
      if (r.left.count(k)) checkSize(path, topic, k + 1, r.left[k].cols, r.left[k].rows, width_, height_);
    } else if (index_.dataset.stereo() && topic == index_.topics.image1) {
      k = r.seen1++;
      if (k < r.needed1.size() && r.needed1[k]) r.right[k] = toGray(r.cursor->image(r.kind1));
      if (r.right.count(k)) checkSize(path, topic, k + 1, r.right[k].cols, r.right[k].rows, width_, height_);
    } else if (masks_ && topic == index_.topics.segmentation) {
      k = r.seen_seg++;
      if (k < r.needed_seg.size() && r.needed_seg[k]) {
        const cv::Mat rgb = toRgb(r.cursor->image(r.kind_seg));
        checkSize(path, topic, k + 1, rgb.cols, rgb.rows, width_, height_);
        r.seg[k] = labelsFromColors(rgb, *masks_);
      }
    }
  } catch (const BagMessageError& e) {
    throw InputError(path, where(topic, k + 1) + ": " + e.what());
  }
}

bool BagSource::nextPairImages(cv::Mat& left, cv::Mat& right, cv::Mat& mask) {
  Reader& r = *reader_;
  const StereoPair& pair = index_.dataset.pairs[next_pair_];
  const bool stereo = index_.dataset.stereo();
  long seg_k = -1;
  if (masks_) {
    seg_k = index_.segmentation_of_pair[next_pair_];
    if (seg_k < 0)
      throw InputError(index_.path,
                       "frame " + std::to_string(next_pair_ + 1) + " (cam0 stamp " + std::to_string(pair.t_ns) +
                           " ns) has no segmentation image with its stamp on '" + index_.topics.segmentation + "'");
  }
  const std::size_t seg_i = static_cast<std::size_t>(std::max(0L, seg_k));
  while (!(r.left.count(pair.i0) && (!stereo || r.right.count(pair.i1)) && (!masks_ || r.seg.count(seg_i)))) {
    if (!r.cursor->next())
      throw InputError(index_.path, "the bag ended before the images of frame " + std::to_string(next_pair_ + 1));
    takeMessage();
  }
  left = std::move(r.left[pair.i0]);
  r.left.erase(r.left.begin(), r.left.upper_bound(pair.i0));
  if (stereo) {
    right = std::move(r.right[pair.i1]);
    r.right.erase(r.right.begin(), r.right.upper_bound(pair.i1));
  }
  if (masks_) {
    mask = std::move(r.seg[seg_i]);
    r.seg.erase(r.seg.begin(), r.seg.upper_bound(seg_i));
  }
  return true;
}

std::optional<Measurement> BagSource::next() {
  const EurocDataset& ds = index_.dataset;
  const bool imu_left = next_imu_ < ds.imu.size();
  const bool frames_left = next_pair_ < ds.pairs.size();
  if (!imu_left && !frames_left) return std::nullopt;
  if (imu_left && (!frames_left || ds.imu[next_imu_].t_ns <= ds.pairs[next_pair_].t_ns))
    return Measurement{ds.imu[next_imu_++]};
  StereoFrame frame;
  frame.t_ns = ds.pairs[next_pair_].t_ns;
  frame.index = next_pair_;
  nextPairImages(frame.left, frame.right, frame.left_mask);
  ++next_pair_;
  return Measurement{std::move(frame)};
}

}  // namespace idyvins::io
