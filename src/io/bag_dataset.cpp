#include "io/bag_dataset.h"

#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <rosbag/bag.h>
#include <rosbag/exceptions.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "core/error.h"
#include "io/bag_structure.h"

namespace idyvins::io {

namespace {

constexpr const char* kImage = "sensor_msgs/Image";
constexpr const char* kCompressed = "sensor_msgs/CompressedImage";
constexpr const char* kImu = "sensor_msgs/Imu";
constexpr const char* kOdometry = "nav_msgs/Odometry";
constexpr const char* kTransform = "geometry_msgs/TransformStamped";
constexpr const char* kPose = "geometry_msgs/PoseStamped";
constexpr const char* kPoint = "geometry_msgs/PointStamped";

TimeNs stampNs(const ros::Time& t) { return static_cast<TimeNs>(t.sec) * 1'000'000'000 + t.nsec; }

void openBag(rosbag::Bag& bag, const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path, "no such bag file");
  {  // rosbag_storage trusts the lengths in the file: check them first
    std::ifstream in(path, std::ios::binary);
    std::error_code ec;
    const auto size = std::filesystem::file_size(path, ec);
    if (!in || ec) throw InputError(path, "cannot open");
    if (const auto problem = bagStructureProblem(in, size))
      throw InputError(path, "not a readable ROS1 bag (truncated or damaged?): " + *problem);
  }
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagUnindexedException&) {
    throw InputError(path, "the bag has no index (recording interrupted?): run `rosbag reindex` on it first");
  } catch (const rosbag::BagException& e) {
    throw InputError(path, std::string("not a readable ROS1 bag (truncated or damaged?): ") + e.what());
  }
}

/// The types of every topic in the bag.
std::map<std::string, std::string> topicTypes(const rosbag::Bag& bag) {
  rosbag::View all(bag);
  std::map<std::string, std::string> types;
  for (const rosbag::ConnectionInfo* c : all.getConnections()) types[c->topic] = c->datatype;
  return types;
}

/// "a, b, c" of the topics whose type is one of `wanted` (or "none").
std::string listTopics(const std::map<std::string, std::string>& types, std::initializer_list<const char*> wanted) {
  std::string out;
  for (const auto& [topic, type] : types)
    for (const char* w : wanted)
      if (type == w) out += (out.empty() ? "" : ", ") + topic + " (" + type + ")";
  return out.empty() ? "none" : out;
}

/// The type of `topic`, checked against `allowed`; InputError naming what the bag has.
std::string checkTopic(const std::string& path, const std::map<std::string, std::string>& types,
                       const std::string& topic, const std::string& key, std::initializer_list<const char*> allowed) {
  const auto it = types.find(topic);
  if (it == types.end())
    throw InputError(path, "topic '" + topic + "' (config key " + key +
                               ") is not in the bag; its image topics: " + listTopics(types, {kImage, kCompressed}) +
                               "; its IMU topics: " + listTopics(types, {kImu}));
  for (const char* a : allowed)
    if (it->second == a) return it->second;
  std::string names;
  for (const char* a : allowed) names += (names.empty() ? "" : " or ") + std::string(a);
  throw InputError(path, "topic '" + topic + "' has type " + it->second + ", expected " + names);
}

/// Strictly increasing stamps per topic.
void checkIncreasing(const std::string& path, const std::string& topic, std::size_t ordinal, TimeNs prev, TimeNs t) {
  if (ordinal > 1 && t <= prev)
    throw InputError(path, "topic '" + topic + "' message " + std::to_string(ordinal) + ": header stamp " +
                               std::to_string(t) + " ns is not after the previous one (" + std::to_string(prev) +
                               " ns); stamps must increase");
}

int channelsOf(const std::string& encoding) {
  if (encoding == "mono8") return 1;
  if (encoding == "rgb8" || encoding == "bgr8") return 3;
  if (encoding == "rgba8" || encoding == "bgra8") return 4;
  return 0;
}

std::string where(const std::string& topic, std::size_t ordinal) {
  return "topic '" + topic + "' message " + std::to_string(ordinal);
}

/// The message as `Msg` (of the topic's declared `type`); InputError when it does not read as one.
template <typename Msg>
boost::shared_ptr<Msg> messageAs(const rosbag::MessageInstance& m, const std::string& type, const std::string& path,
                                 const std::string& topic, std::size_t ordinal) {
  auto msg = m.instantiate<Msg>();
  if (!msg) throw InputError(path, where(topic, ordinal) + ": cannot be read as " + type);
  return msg;
}

void checkSize(const std::string& path, const std::string& topic, std::size_t ordinal, int width, int height,
               int expected_width, int expected_height) {
  if (expected_width > 0 && (width != expected_width || height != expected_height))
    throw InputError(path, where(topic, ordinal) + ": image is " + std::to_string(width) + "x" +
                               std::to_string(height) + ", the config says " + std::to_string(expected_width) + "x" +
                               std::to_string(expected_height));
}

/// An uncompressed image as 8-bit gray (OpenCV's colour conversion).
cv::Mat toGray(const sensor_msgs::Image& m, const std::string& path, const std::string& topic, std::size_t ordinal) {
  const int ch = channelsOf(m.encoding);
  if (ch == 0)
    throw InputError(path, where(topic, ordinal) + ": unsupported image encoding '" + m.encoding +
                               "' (supported: mono8, rgb8, bgr8, rgba8, bgra8)");
  if (m.step < m.width * static_cast<std::uint32_t>(ch) || m.data.size() < static_cast<std::size_t>(m.step) * m.height)
    throw InputError(path, where(topic, ordinal) + ": image data is shorter than height x step");
  const cv::Mat wrapped(static_cast<int>(m.height), static_cast<int>(m.width), CV_8UC(ch),
                        const_cast<std::uint8_t*>(m.data.data()), m.step);
  cv::Mat gray;
  if (ch == 1)
    gray = wrapped.clone();
  else if (m.encoding == "rgb8")
    cv::cvtColor(wrapped, gray, cv::COLOR_RGB2GRAY);
  else if (m.encoding == "bgr8")
    cv::cvtColor(wrapped, gray, cv::COLOR_BGR2GRAY);
  else if (m.encoding == "rgba8")
    cv::cvtColor(wrapped, gray, cv::COLOR_RGBA2GRAY);
  else
    cv::cvtColor(wrapped, gray, cv::COLOR_BGRA2GRAY);
  return gray;
}

bool supportedCompression(const std::string& format) {
  return format.find("png") != std::string::npos || format.find("jpeg") != std::string::npos ||
         format.find("jpg") != std::string::npos;
}

/// A png or jpeg image as 8-bit gray.
cv::Mat toGray(const sensor_msgs::CompressedImage& m, const std::string& path, const std::string& topic,
               std::size_t ordinal) {
  if (!supportedCompression(m.format))
    throw InputError(
        path, where(topic, ordinal) + ": unsupported compressed format '" + m.format + "' (supported: png, jpeg)");
  const cv::Mat decoded = cv::imdecode(m.data, cv::IMREAD_UNCHANGED);
  if (decoded.empty() || decoded.depth() != CV_8U)
    throw InputError(path, where(topic, ordinal) + ": the " + m.format + " data does not decode to an 8-bit image");
  cv::Mat gray;
  if (decoded.channels() == 1)
    gray = decoded;
  else if (decoded.channels() == 3)
    cv::cvtColor(decoded, gray, cv::COLOR_BGR2GRAY);
  else
    cv::cvtColor(decoded, gray, cv::COLOR_BGRA2GRAY);
  return gray;
}

/// The records of an image topic in bag order; `stamp_of(message, ordinal)` checks one message and
/// returns its header stamp. Stamps must increase strictly.
template <typename StampOf>
std::vector<ImageRecord> indexImageTopic(const rosbag::Bag& bag, const std::string& path, const std::string& topic,
                                         StampOf stamp_of) {
  std::vector<ImageRecord> records;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  TimeNs prev = 0;
  for (const rosbag::MessageInstance& m : view) {
    const std::size_t ordinal = records.size() + 1;
    const TimeNs t = stamp_of(m, ordinal);
    checkIncreasing(path, topic, ordinal, prev, t);
    prev = t;
    ImageRecord r;
    r.t_ns = t;
    r.path = path + ":" + topic;
    r.csv_line = static_cast<int>(ordinal);
    r.exists = true;
    records.push_back(std::move(r));
  }
  return records;
}

/// Header stamps (and the encoding and size checks) of a camera's image topic.
std::vector<ImageRecord> indexImages(const rosbag::Bag& bag, const std::string& path, const std::string& topic,
                                     const std::string& type, int expected_width, int expected_height) {
  return indexImageTopic(bag, path, topic, [&](const rosbag::MessageInstance& m, std::size_t ordinal) {
    if (type == kImage) {
      const auto img = messageAs<sensor_msgs::Image>(m, type, path, topic, ordinal);
      if (channelsOf(img->encoding) == 0)
        throw InputError(path, where(topic, ordinal) + ": unsupported image encoding '" + img->encoding +
                                   "' (supported: mono8, rgb8, bgr8, rgba8, bgra8)");
      checkSize(path, topic, ordinal, static_cast<int>(img->width), static_cast<int>(img->height), expected_width,
                expected_height);
      return stampNs(img->header.stamp);
    }
    const auto img = messageAs<sensor_msgs::CompressedImage>(m, type, path, topic, ordinal);
    if (!supportedCompression(img->format))
      throw InputError(
          path, where(topic, ordinal) + ": unsupported compressed format '" + img->format + "' (supported: png, jpeg)");
    return stampNs(img->header.stamp);
  });
}

/// Header stamps of the segmentation topic (strictly increasing).
std::vector<ImageRecord> indexSegmentation(const rosbag::Bag& bag, const std::string& path, const std::string& topic,
                                           const std::string& type) {
  return indexImageTopic(bag, path, topic, [&](const rosbag::MessageInstance& m, std::size_t ordinal) {
    return stampNs(type == kImage
                       ? messageAs<sensor_msgs::Image>(m, type, path, topic, ordinal)->header.stamp
                       : messageAs<sensor_msgs::CompressedImage>(m, type, path, topic, ordinal)->header.stamp);
  });
}

std::vector<ImuSample> indexImu(const rosbag::Bag& bag, const std::string& path, const std::string& topic) {
  std::vector<ImuSample> imu;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) {
    const auto msg = m.instantiate<sensor_msgs::Imu>();
    const std::size_t ordinal = imu.size() + 1;
    if (!msg) throw InputError(path, where(topic, ordinal) + ": cannot be read as sensor_msgs/Imu");
    ImuSample s;
    s.t_ns = stampNs(msg->header.stamp);
    checkIncreasing(path, topic, ordinal, imu.empty() ? 0 : imu.back().t_ns, s.t_ns);
    s.gyr_b = {msg->angular_velocity.x, msg->angular_velocity.y, msg->angular_velocity.z};
    s.acc_b = {msg->linear_acceleration.x, msg->linear_acceleration.y, msg->linear_acceleration.z};
    if (!s.gyr_b.allFinite() || !s.acc_b.allFinite())
      throw InputError(path, where(topic, ordinal) + ": non-finite angular velocity or acceleration");
    imu.push_back(s);
  }
  return imu;
}

GroundTruthState poseState(TimeNs t, double px, double py, double pz, double qw, double qx, double qy, double qz) {
  GroundTruthState g;
  g.t_ns = t;
  g.p_w_b = {px, py, pz};
  g.q_w_b = Eigen::Quaterniond(qw, qx, qy, qz);
  if (g.q_w_b.norm() < 1e-9) g.q_w_b = Eigen::Quaterniond::Identity();
  g.q_w_b.normalize();
  return g;
}

std::vector<GroundTruthState> indexGroundTruth(const rosbag::Bag& bag, const std::string& path,
                                               const std::string& topic, const std::string& type) {
  std::vector<GroundTruthState> gt;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) {
    const std::size_t ordinal = gt.size() + 1;
    GroundTruthState g;
    bool ok = false;
    if (type == kOdometry) {
      if (const auto o = m.instantiate<nav_msgs::Odometry>()) {
        const auto& p = o->pose.pose;
        g = poseState(stampNs(o->header.stamp), p.position.x, p.position.y, p.position.z, p.orientation.w,
                      p.orientation.x, p.orientation.y, p.orientation.z);
        ok = true;
      }
    } else if (type == kTransform) {
      if (const auto o = m.instantiate<geometry_msgs::TransformStamped>()) {
        const auto& tr = o->transform;
        g = poseState(stampNs(o->header.stamp), tr.translation.x, tr.translation.y, tr.translation.z, tr.rotation.w,
                      tr.rotation.x, tr.rotation.y, tr.rotation.z);
        ok = true;
      }
    } else if (type == kPose) {
      if (const auto o = m.instantiate<geometry_msgs::PoseStamped>()) {
        const auto& p = o->pose;
        g = poseState(stampNs(o->header.stamp), p.position.x, p.position.y, p.position.z, p.orientation.w,
                      p.orientation.x, p.orientation.y, p.orientation.z);
        ok = true;
      }
    } else if (const auto o = m.instantiate<geometry_msgs::PointStamped>()) {
      g = poseState(stampNs(o->header.stamp), o->point.x, o->point.y, o->point.z, 1, 0, 0, 0);
      ok = true;
    }
    if (!ok) throw InputError(path, where(topic, ordinal) + ": cannot be read as " + type);
    checkIncreasing(path, topic, ordinal, gt.empty() ? 0 : gt.back().t_ns, g.t_ns);
    if (!g.p_w_b.allFinite()) throw InputError(path, where(topic, ordinal) + ": non-finite position");
    gt.push_back(g);
  }
  return gt;
}

/// A segmentation image as CV_8UC3 in RGB order.
cv::Mat toRgb(const rosbag::MessageInstance& m, const std::string& type, const std::string& path,
              const std::string& topic, std::size_t ordinal) {
  cv::Mat rgb;
  if (type == kImage) {
    const auto img = messageAs<sensor_msgs::Image>(m, type, path, topic, ordinal);
    const int ch = channelsOf(img->encoding);
    if (ch < 3)
      throw InputError(path, where(topic, ordinal) + ": segmentation encoding '" + img->encoding +
                                 "' is not a colour one (rgb8, bgr8, rgba8, bgra8)");
    if (img->step < img->width * static_cast<std::uint32_t>(ch) ||
        img->data.size() < static_cast<std::size_t>(img->step) * img->height)
      throw InputError(path, where(topic, ordinal) + ": image data is shorter than height x step");
    const cv::Mat wrapped(static_cast<int>(img->height), static_cast<int>(img->width), CV_8UC(ch),
                          const_cast<std::uint8_t*>(img->data.data()), img->step);
    if (img->encoding == "rgb8")
      rgb = wrapped.clone();
    else if (img->encoding == "bgr8")
      cv::cvtColor(wrapped, rgb, cv::COLOR_BGR2RGB);
    else if (img->encoding == "rgba8")
      cv::cvtColor(wrapped, rgb, cv::COLOR_RGBA2RGB);
    else
      cv::cvtColor(wrapped, rgb, cv::COLOR_BGRA2RGB);
  } else {
    const auto img = messageAs<sensor_msgs::CompressedImage>(m, type, path, topic, ordinal);
    const cv::Mat bgr = cv::imdecode(img->data, cv::IMREAD_COLOR);
    if (bgr.empty()) throw InputError(path, where(topic, ordinal) + ": the " + img->format + " data does not decode");
    cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  }
  return rgb;
}

}  // namespace

bool isBagFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  std::ifstream in(path, std::ios::binary);
  char magic[13] = {};
  in.read(magic, 13);
  return in.gcount() == 13 && std::string(magic, 13) == "#ROSBAG V2.0\n";
}

BagIndex indexBag(const std::string& path, const BagTopics& topics, int expected_width, int expected_height,
                  const EurocOptions& options) {
  rosbag::Bag bag;
  openBag(bag, path);
  BagIndex index;
  index.path = path;
  index.topics = topics;
  try {
    const std::map<std::string, std::string> types = topicTypes(bag);
    if (types.empty()) throw InputError(path, "the bag holds no messages");
    for (const auto& [topic, type] : types) {
      rosbag::View v(bag, rosbag::TopicQuery(topic));
      index.all_topics.push_back({topic, type, v.size()});
    }
    const std::string t0 = checkTopic(path, types, topics.image0, "image0_topic", {kImage, kCompressed});
    const std::string ti = checkTopic(path, types, topics.imu, "imu_topic", {kImu});
    (void)ti;
    EurocDataset& ds = index.dataset;
    ds.root = path;
    ds.imu = indexImu(bag, path, topics.imu);
    ds.cam0 = indexImages(bag, path, topics.image0, t0, expected_width, expected_height);
    if (!topics.image1.empty()) {
      const std::string t1 = checkTopic(path, types, topics.image1, "image1_topic", {kImage, kCompressed});
      ds.cam1 = indexImages(bag, path, topics.image1, t1, expected_width, expected_height);
    }
    if (!topics.groundtruth.empty()) {
      const std::string tg =
          checkTopic(path, types, topics.groundtruth, "groundtruth_topic", {kOdometry, kTransform, kPose, kPoint});
      ds.groundtruth = indexGroundTruth(bag, path, topics.groundtruth, tg);
      ds.has_groundtruth = !ds.groundtruth.empty();
    }
    if (!topics.segmentation.empty()) {
      const std::string ts = checkTopic(path, types, topics.segmentation, "segmentation_topic", {kImage, kCompressed});
      index.segmentation = indexSegmentation(bag, path, topics.segmentation, ts);
    }
    if (ds.cam0.empty()) throw InputError(path, "topic '" + topics.image0 + "' holds no images");
    if (ds.imu.empty()) throw InputError(path, "topic '" + topics.imu + "' holds no IMU samples");
    if (ds.stereo()) {
      pairByTime(ds.cam0, ds.cam1, options.pair_tolerance_ns, ds.pairs, ds.unmatched0, ds.unmatched1);
    } else {
      for (std::size_t i = 0; i < ds.cam0.size(); ++i) ds.pairs.push_back({ds.cam0[i].t_ns, i, 0});
    }
    if (!index.segmentation.empty()) {  // each frame's segmentation: the one with cam0's stamp
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
  } catch (const rosbag::BagException& e) {
    throw InputError(path, std::string("reading the bag failed (truncated or damaged?): ") + e.what());
  }
  return index;
}

/// The open bag, a view over the image topics in bag order, and the decoded images
/// waiting for their partner (by position on their topic).
struct BagSource::Reader {
  rosbag::Bag bag;
  std::unique_ptr<rosbag::View> view;
  rosbag::View::iterator it;
  std::string type0, type1, type_seg;
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
  openBag(reader_->bag, index_.path);
  std::vector<std::string> topics{index_.topics.image0};
  if (index_.dataset.stereo()) topics.push_back(index_.topics.image1);
  if (masks_) topics.push_back(index_.topics.segmentation);
  reader_->view = std::make_unique<rosbag::View>(reader_->bag, rosbag::TopicQuery(topics));
  reader_->it = reader_->view->begin();
  for (const auto& t : index_.all_topics) {
    if (t.topic == index_.topics.image0) reader_->type0 = t.type;
    if (t.topic == index_.topics.image1) reader_->type1 = t.type;
    if (t.topic == index_.topics.segmentation) reader_->type_seg = t.type;
  }
  reader_->needed_seg.assign(index_.segmentation.size(), false);
  if (masks_)
    for (long k : index_.segmentation_of_pair)
      if (k >= 0) reader_->needed_seg[static_cast<std::size_t>(k)] = true;
  reader_->needed0.assign(index_.dataset.cam0.size(), false);
  reader_->needed1.assign(index_.dataset.cam1.size(), false);
  for (const auto& p : index_.dataset.pairs) {
    reader_->needed0[p.i0] = true;
    if (index_.dataset.stereo()) reader_->needed1[p.i1] = true;
  }
}

namespace {
/// One image message as 8-bit gray, of the expected size; InputError otherwise.
cv::Mat grayImage(const rosbag::MessageInstance& m, const std::string& type, const std::string& path,
                  const std::string& topic, std::size_t ordinal, int width, int height) {
  cv::Mat gray;
  if (type == kImage) {
    const auto img = messageAs<sensor_msgs::Image>(m, type, path, topic, ordinal);
    gray = toGray(*img, path, topic, ordinal);
  } else {
    const auto img = messageAs<sensor_msgs::CompressedImage>(m, type, path, topic, ordinal);
    gray = toGray(*img, path, topic, ordinal);
  }
  checkSize(path, topic, ordinal, gray.cols, gray.rows, width, height);
  return gray;
}

}  // namespace

BagSource::~BagSource() = default;

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
  const std::string& path = index_.path;
  auto decode = [&](const rosbag::MessageInstance& m, const std::string& type, const std::string& topic,
                    std::size_t ordinal) { return grayImage(m, type, path, topic, ordinal, width_, height_); };
  try {
    while (!(r.left.count(pair.i0) && (!stereo || r.right.count(pair.i1)) && (!masks_ || r.seg.count(seg_i)))) {
      if (r.it == r.view->end())
        throw InputError(path, "the bag ended before the images of frame " + std::to_string(next_pair_ + 1));
      const rosbag::MessageInstance& m = *r.it;
      if (m.getTopic() == index_.topics.image0) {
        const std::size_t k = r.seen0++;
        if (k < r.needed0.size() && r.needed0[k]) r.left[k] = decode(m, r.type0, m.getTopic(), k + 1);
      } else if (stereo && m.getTopic() == index_.topics.image1) {
        const std::size_t k = r.seen1++;
        if (k < r.needed1.size() && r.needed1[k]) r.right[k] = decode(m, r.type1, m.getTopic(), k + 1);
      } else if (masks_ && m.getTopic() == index_.topics.segmentation) {
        const std::size_t k = r.seen_seg++;
        if (k < r.needed_seg.size() && r.needed_seg[k]) {
          const cv::Mat rgb = toRgb(m, r.type_seg, path, m.getTopic(), k + 1);
          checkSize(path, m.getTopic(), k + 1, rgb.cols, rgb.rows, width_, height_);
          r.seg[k] = labelsFromColors(rgb, *masks_);
        }
      }
      ++r.it;
    }
  } catch (const rosbag::BagException& e) {
    throw InputError(path, std::string("reading the bag failed (truncated or damaged?): ") + e.what());
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
