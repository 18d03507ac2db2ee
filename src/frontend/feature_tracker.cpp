#include "frontend/feature_tracker.h"

#include <algorithm>
#include <chrono>
#include <numeric>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <unordered_map>

#include "camera/stereo.h"
#include "core/so3.h"
#include "frontend/corner_detector.h"

namespace idyvins::frontend {

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }
Eigen::Vector2d toEigen(const cv::Point2f& p) { return {p.x, p.y}; }
/// Feature::match_shape's stretch along an edge at most (10× the noise of the textured
/// direction): beyond it the position along the edge is not measured at all.
constexpr double kMaxMatchShapeRatio = 100.0;
/// Counts a track of `length` frames ended for `reason` (new corners: length 1).
void countLoss(FeatureFrame& out, int length, std::size_t TrackLosses::*reason) {
  ++(out.lost_tracks.*reason);
  if (length == 1) ++(out.lost_new.*reason);
}

}  // namespace

FeatureTracker::FeatureTracker(const camera::Rig& rig, const TrackerParams& params) : params_(params) {
  for (const auto& c : rig.cams) cams_.push_back(camera::makeCamera(c));
  if (!rig.cams.empty()) {
    image_width_ = rig.cams[0].width;
    image_height_ = rig.cams[0].height;
    lens_mask_ = lensMask(*cams_[0], image_width_, image_height_, params.corner_margin_px, params.max_ray_angle_deg);
  }
  if (rig.stereo()) {
    T_c1_c0_ = rig.T_b_c[1].inverse() * rig.T_b_c[0];
    E_c1_c0_ = hat(T_c1_c0_.translation()) * T_c1_c0_.linear();
  }
  if (params.equalize) clahe_ = cv::createCLAHE(3.0, cv::Size(8, 8));  // VINS-Mono's setting
}

Feature FeatureTracker::featureOf(const Track& t, FeatureLabel label) {
  Feature f;
  f.id = t.id;
  f.uv = toEigen(t.uv);
  f.xy = t.xy;
  f.track_length = t.length;
  f.label = label;
  return f;
}

void FeatureTracker::reset() {
  prev_pyr_.clear();
  prev_left_.release();
  prev_tracks_.clear();
  followed_.clear();
}

bool FeatureTracker::movesWithEliminated(const Track& t, const std::vector<Track>& kept, int radius) const {
  for (const Track& k : kept) {
    if (!followed_.count(k.id)) continue;
    const double dx = k.uv.x - t.uv.x, dy = k.uv.y - t.uv.y;
    if (dx * dx + dy * dy > static_cast<double>(radius) * radius) continue;
    if ((k.flow - t.flow).norm() <= params_.move_with_eliminated_px) return true;
  }
  return false;
}

AlignOptions FeatureTracker::alignOptions() const {
  AlignOptions o;
  o.min_inside = params_.patch_min_inside;
  return o;
}

bool FeatureTracker::inBorder(const cv::Point2f& p) const {
  const int b = params_.border_px;
  return p.x >= b && p.y >= b && p.x < image_width_ - b && p.y < image_height_ - b &&
         (lens_mask_.empty() || lens_mask_.at<std::uint8_t>(cvRound(p.y), cvRound(p.x)) != 0);  // a fisheye's rim
}

void FeatureTracker::trackPrevious(const std::vector<cv::Mat>& pyr, const cv::Mat& image, std::vector<Track>& tracks,
                                   std::vector<PrevObs>& prev, std::vector<const Track*>& lost, FeatureFrame& out) {
  if (prev_pyr_.empty() || prev_tracks_.empty()) return;
  std::vector<cv::Point2f> p0, p1, back;
  for (const auto& t : prev_tracks_) p0.push_back(t.uv);
  std::vector<uchar> status, status_back;
  std::vector<float> err;
  const cv::Size win(params_.klt_window, params_.klt_window);
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, params_.klt_iterations,
                              params_.klt_epsilon);
  const std::vector<cv::Mat>* to = &pyr;
  if (params_.temporal_gain_compensation && !prev_left_.empty()) {
    const cv::Mat matched = matchBrightness(image, prev_left_);
    if (matched.data != image.data) {
      cv::buildOpticalFlowPyramid(matched, matched_pyr_, win, params_.klt_max_level);
      to = &matched_pyr_;
    }
  }
  cv::calcOpticalFlowPyrLK(prev_pyr_, *to, p0, p1, status, err, win, params_.klt_max_level, crit);
  if (params_.flow_back) {
    back = p0;
    cv::calcOpticalFlowPyrLK(*to, prev_pyr_, p1, back, status_back, err, win, params_.klt_back_max_level, crit,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
  }
  for (std::size_t i = 0; i < p0.size(); ++i) {
    const Track& old = prev_tracks_[i];
    std::size_t TrackLosses::*reason = nullptr;
    if (!status[i])
      reason = &TrackLosses::klt;
    else if (!inBorder(p1[i]))
      reason = &TrackLosses::border;
    else if (params_.flow_back && !(status_back[i] && cv::norm(back[i] - p0[i]) <= params_.flow_back_px))
      reason = &TrackLosses::backward;
    Eigen::Matrix2d A_patch;
    Eigen::Vector2d xy;
    if (!reason) reason = continueTrack(old, image, p1[i], A_patch, xy);
    if (reason) {
      countLoss(out, old.length, reason);
      lost.push_back(&old);
      continue;
    }
    tracks.push_back({old.id, p1[i], xy, old.length + 1, old.patch, A_patch});
    tracks.back().flow = toEigen(p1[i]) - toEigen(old.uv);
    prev.push_back({toEigen(old.uv), old.xy, old.has_right, old.xy_right, old.uv_right});
  }
}

std::size_t TrackLosses::*FeatureTracker::continueTrack(const Track& old, const cv::Mat& image, cv::Point2f& p1,
                                                        Eigen::Matrix2d& A_patch, Eigen::Vector2d& xy) const {
  A_patch = old.A_patch;
  if (params_.align_first_patch && old.patch) {
    AffineWarp warp{old.A_patch, toEigen(p1)};
    const AlignResult r = alignAffine(*old.patch, image, warp, alignOptions());
    if (!r.converged || r.zncc < params_.min_patch_zncc ||
        (warp.t - toEigen(p1)).norm() > params_.max_patch_correction_px)
      return &TrackLosses::alignment;
    p1 = cv::Point2f(static_cast<float>(warp.t.x()), static_cast<float>(warp.t.y()));
    A_patch = warp.A;
  }
  if (!inBorder(p1) || !cams_[0]->liftToNormalized(toEigen(p1), xy)) return &TrackLosses::border;
  return nullptr;
}

/// The tracker's measurements for the lost-corner test of one frame (LostCornerProbe).
class FeatureTracker::Probe final : public LostCornerProbe {
 public:
  Probe(const FeatureTracker& tracker, const cv::Mat& image, const std::vector<const Track*>& corners)
      : tr_(tracker), image_(image), corners_(corners) {}
  bool searchable(const Eigen::Vector2d& uv) const override {
    const double margin = tr_.params_.patch_half + 2;
    return uv.x() >= margin && uv.y() >= margin && uv.x() < tr_.image_width_ - margin &&
           uv.y() < tr_.image_height_ - margin;
  }
  std::vector<LostCornerFinding> find(const std::vector<LostCornerSearch>& searches) override;
  std::vector<double> depthAt(const std::vector<LostCornerSearch>& searches) override;

 private:
  const FeatureTracker& tr_;
  const cv::Mat& image_;
  const std::vector<const Track*>& corners_;
};

std::vector<LostCornerFinding> FeatureTracker::Probe::find(const std::vector<LostCornerSearch>& searches) {
  // KLT started at the prediction (a wider basin than the patch alignment alone).
  std::vector<cv::Point2f> p0, p1;
  for (const auto& q : searches) {
    p0.push_back(corners_[q.corner]->uv);
    p1.emplace_back(static_cast<float>(q.uv_pred.x()), static_cast<float>(q.uv_pred.y()));
  }
  const std::vector<uchar> status = tr_.kltFromGuess(tr_.prev_pyr_, tr_.cur_pyr_, p0, p1);
  std::vector<LostCornerFinding> out(searches.size());
  for (std::size_t i = 0; i < searches.size(); ++i) {
    const Track& t = *corners_[searches[i].corner];
    const Eigen::Vector2d& pred = searches[i].uv_pred;
    LostCornerFinding& f = out[i];
    auto foundFrom = [&](const Eigen::Vector2d& start) {
      AffineWarp warp{t.A_patch, start};
      const AlignResult r = alignAffine(*t.patch, image_, warp, tr_.alignOptions());
      if ((warp.t - pred).norm() > searches[i].tol_px) return false;
      f.best_zncc = std::max(f.best_zncc, r.zncc);
      return r.converged && r.zncc >= tr_.params_.min_patch_zncc;
    };
    f.found = foundFrom(pred) ||
              (status[i] && (toEigen(p1[i]) - pred).norm() <= searches[i].tol_px && foundFrom(toEigen(p1[i])));
  }
  return out;
}

std::vector<double> FeatureTracker::Probe::depthAt(const std::vector<LostCornerSearch>& searches) {
  std::vector<double> depth(searches.size(), 0.0);
  if (!tr_.has_right_image_ || searches.empty()) return depth;
  std::vector<cv::Point2f> pl, pr;
  for (const auto& q : searches) {
    pl.emplace_back(static_cast<float>(q.uv_pred.x()), static_cast<float>(q.uv_pred.y()));
    Eigen::Vector2d uv_r = q.uv_pred;
    tr_.cams_[1]->project(tr_.T_c1_c0_ * q.p_pred, uv_r);
    pr.emplace_back(static_cast<float>(uv_r.x()), static_cast<float>(uv_r.y()));
  }
  const std::vector<uchar> st = tr_.kltFromGuess(tr_.cur_pyr_, tr_.right_pyr_, pl, pr);
  for (std::size_t j = 0; j < searches.size(); ++j) {
    Eigen::Vector2d xy_l, xy_r;
    double d;
    if (st[j] && tr_.cams_[0]->liftToNormalized(searches[j].uv_pred, xy_l) &&
        tr_.cams_[1]->liftToNormalized(toEigen(pr[j]), xy_r) && camera::stereoDepth(xy_l, xy_r, tr_.T_c1_c0_, d))
      depth[j] = d;
  }
  return depth;
}

void FeatureTracker::judgeLost(const cv::Mat& image, const std::vector<const Track*>& lost, FrameWork& w) const {
  std::vector<const Track*> corners;  // new corners (one frame) with a right match and a first patch
  std::vector<LostCorner> seen;
  for (const Track* t : lost) {
    if (t->length != 1 || !t->has_right || !t->patch || cams_.size() < 2) continue;  // longer tracks were scored
    corners.push_back(t);
    seen.push_back({toEigen(t->uv), t->xy, t->xy_right});
  }
  if (corners.empty() || !w.filter) return;
  Probe probe(*this, image, corners);
  const LostCornerJudgement j = w.filter->judgeLost(w.ctx, seen, probe);
  w.out.lost_tested = j.tested;
  for (std::size_t i : j.moving) {
    const Track& t = *corners[i];
    Feature f = featureOf(t, FeatureLabel::kEliminated);
    f.has_right = true;
    f.xy_right = t.xy_right;
    w.out.lost_moving.push_back(f);
  }
}

std::vector<uchar> FeatureTracker::kltFromGuess(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                                const std::vector<cv::Point2f>& p0,
                                                std::vector<cv::Point2f>& p1) const {
  std::vector<uchar> status;
  std::vector<float> err;
  const cv::Size win(params_.klt_window, params_.klt_window);
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, params_.klt_iterations,
                              params_.klt_epsilon);
  cv::calcOpticalFlowPyrLK(from, to, p0, p1, status, err, win, params_.klt_max_level, crit,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  return status;
}

void FeatureTracker::detectNew(const cv::Mat& image, std::vector<Track>& tracks, FeatureFrame& out,
                               std::vector<const Track*>& with_eliminated) {
  // Keep long tracks first; drop tracks closer than min_dist to a longer one.
  std::vector<std::size_t> order(tracks.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return tracks[a].length > tracks[b].length; });
  detect_mask_.create(image.size(), CV_8UC1);
  if (!lens_mask_.empty()) detect_mask_.setTo(cv::Scalar(0));
  detect_mask_.setTo(cv::Scalar(255), lens_mask_);  // an empty lens mask: the whole image
  cv::Mat& mask = detect_mask_;
  const int r = static_cast<int>(params_.min_dist);
  std::vector<Track> kept;
  const bool judge_pruned =
      params_.lost_track_test && params_.follow_eliminated && params_.move_with_eliminated_px > 0 && !followed_.empty();
  for (std::size_t i : order) {
    const cv::Point pt(cvRound(tracks[i].uv.x), cvRound(tracks[i].uv.y));
    if (mask.at<uchar>(pt) != 255) {
      countLoss(out, tracks[i].length - 1, &TrackLosses::pruned);
      if (judge_pruned && tracks[i].length == 2 && movesWithEliminated(tracks[i], kept, r)) {
        const auto old = std::find_if(prev_tracks_.begin(), prev_tracks_.end(),
                                      [&](const Track& p) { return p.id == tracks[i].id; });
        if (old != prev_tracks_.end()) with_eliminated.push_back(&*old);
      }
      continue;
    }
    kept.push_back(tracks[i]);
    cv::circle(mask, pt, r, cv::Scalar(0), cv::FILLED);
  }
  tracks = std::move(kept);
  if (params_.align_first_patch && params_.corner_margin_px > 0) {
    const int b = std::min({params_.corner_margin_px, mask.cols / 2, mask.rows / 2});
    mask.rowRange(0, b).setTo(cv::Scalar(0));
    mask.rowRange(mask.rows - b, mask.rows).setTo(cv::Scalar(0));
    mask.colRange(0, b).setTo(cv::Scalar(0));
    mask.colRange(mask.cols - b, mask.cols).setTo(cv::Scalar(0));
  }
  const int n_max = params_.max_cnt - static_cast<int>(tracks.size());
  std::size_t& detected = out.detected;
  detected = 0;
  if (n_max <= 0) return;
  CornerOptions corner_options;
  corner_options.max_corners = n_max;
  corner_options.quality_level = 0.01;
  corner_options.min_distance = params_.min_dist;
  const std::vector<cv::Point2f> corners = detectCorners(image, mask, corner_options);
  for (const auto& c : corners) {
    Eigen::Vector2d xy;
    if (!inBorder(c) || !cams_[0]->liftToNormalized(toEigen(c), xy)) continue;
    Track t{next_id_++, c, xy, 1, nullptr, Eigen::Matrix2d::Identity(), false, false, Eigen::Vector2d::Zero()};
    if (params_.align_first_patch) {
      auto patch = std::make_shared<PatchTemplate>(
          makePatchTemplate(image, toEigen(c), params_.patch_half, params_.patch_min_inside));
      if (patch->valid) t.patch = std::move(patch);
    }
    tracks.push_back(std::move(t));
    ++detected;
  }
}

void FeatureTracker::refineRight(const cv::Mat& left, const Eigen::Vector2d& uv, cv::Point2f& uv_right) const {
  const PatchTemplate tmpl = makePatchTemplate(left, uv, params_.patch_half, params_.patch_min_inside);
  AffineWarp warp;
  warp.t = toEigen(uv_right);
  AlignOptions align = alignOptions();
  if (params_.stereo_refine == 2) align.model = WarpModel::kTranslation;
  if (tmpl.valid && alignAffine(tmpl, right_pyr_[0], warp, align).converged &&
      (warp.t - toEigen(uv_right)).norm() < 1.0)
    uv_right = cv::Point2f(static_cast<float>(warp.t.x()), static_cast<float>(warp.t.y()));
}

void FeatureTracker::matchRight(const std::vector<cv::Mat>& left_pyr, std::vector<Feature>& features,
                                const std::vector<std::size_t>* which) {
  if (!has_right_image_) return;
  std::vector<std::size_t> all;
  if (!which) {
    all.resize(features.size());
    std::iota(all.begin(), all.end(), 0);
    which = &all;
  }
  if (which->empty()) return;
  const cv::Size win(params_.klt_window, params_.klt_window);
  const cv::TermCriteria crit(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, params_.klt_iterations,
                              params_.klt_epsilon);
  const std::vector<cv::Mat>& right_pyr = right_pyr_;  // built once per frame in track()
  const std::size_t n = which->size();
  std::vector<cv::Point2f> pl(n), pr(n), back;
  std::vector<uchar> status(n, 0), status_back;
  std::vector<float> err;
  for (std::size_t i = 0; i < n; ++i)
    pl[i] =
        cv::Point2f(static_cast<float>(features[(*which)[i]].uv.x()), static_cast<float>(features[(*which)[i]].uv.y()));
  cv::calcOpticalFlowPyrLK(left_pyr, right_pyr, pl, pr, status, err, win, params_.klt_max_level, crit, 0);
  for (std::size_t i = 0; i < n; ++i) status[i] = status[i] && inBorder(pr[i]);
  if (params_.flow_back) {
    back = pl;
    cv::calcOpticalFlowPyrLK(right_pyr, left_pyr, pr, back, status_back, err, win, params_.klt_back_max_level, crit,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
  }
  const double f = cams_[1]->focal();
  for (std::size_t i = 0; i < n; ++i) {
    Feature& feat = features[(*which)[i]];
    feat.has_right = feat.right_low_zncc = false;
    bool ok = status[i] != 0;
    if (ok && params_.flow_back) ok = status_back[i] && cv::norm(back[i] - pl[i]) <= params_.flow_back_px;
    if (ok && params_.stereo_refine != 0) refineRight(left_pyr[0], feat.uv, pr[i]);
    Eigen::Vector2d xy_r;
    if (!ok || !cams_[1]->liftToNormalized(toEigen(pr[i]), xy_r)) continue;
    // Epipolar check with the known extrinsics (distance to the line, in pixels).
    const Eigen::Vector3d x0(feat.xy.x(), feat.xy.y(), 1.0), x1(xy_r.x(), xy_r.y(), 1.0);
    const Eigen::Vector3d line = E_c1_c0_ * x0;
    const double dist = std::abs(x1.dot(line)) / std::max(line.head<2>().norm(), 1e-12);
    if (dist * f > params_.stereo_epipolar_px) continue;
    const bool correlates = params_.stereo_min_zncc <= -1.0 ||
                            patchZncc(left_pyr[0], feat.uv, right_pyr[0], toEigen(pr[i]), params_.patch_half,
                                      params_.patch_min_inside) >= params_.stereo_min_zncc;
    if (!correlates && !params_.stereo_zncc_motion_only) continue;
    feat.has_right = correlates;
    feat.right_low_zncc = !correlates;
    feat.uv_right = toEigen(pr[i]);
    feat.xy_right = xy_r;
    feat.match_shape = matchShape(left_pyr[0], feat.uv, params_.patch_half, kMaxMatchShapeRatio);
  }
}

FeatureFrame FeatureTracker::track(const StereoFrame& input, const MotionPrior& prior, FeatureFilter* filter,
                                   const cv::Mat* mask) {
  const auto start = Clock::now();
  StereoFrame frame = input;  // images are reference-counted: no copy unless equalized
  if (clahe_) {               // into new images: frame's share the caller's pixels
    cv::Mat left, right;
    clahe_->apply(input.left, left);
    if (!input.right.empty()) clahe_->apply(input.right, right);
    frame.left = left;
    frame.right = right;
  }
  FrameWork w{FeatureFrame{}, filter, FilterContext{cams_[0].get(), &prior, mask, prev_t_ns_, frame.t_ns}, {}, 0.0};
  w.out.t_ns = frame.t_ns;
  buildPyramids(frame);
  std::vector<Track> tracks;
  std::vector<PrevObs> prev;
  std::vector<const Track*> lost;  // into prev_tracks_
  trackPrevious(cur_pyr_, frame.left, tracks, prev, lost, w.out);
  if (params_.lost_track_test && !lost.empty()) {
    const auto t0 = Clock::now();
    judgeLost(frame.left, lost, w);
    w.filter_ms = msSince(t0);  // judging lost new corners counts as dynamic preprocessing
  }
  w.out.tracked = tracks.size();
  std::vector<Track> followed = separateFollowed(tracks, prev);
  const double dt = prev_pyr_.empty() ? 0.0 : toSeconds(frame.t_ns - prev_t_ns_);

  // Rejection filter on tracked features (before the top-up, so holes refill now).
  std::vector<Feature> tracked_feats;
  filterTracks(w, tracks, &prev, tracked_feats);
  std::unordered_map<std::uint64_t, Feature> carried;  // id -> feature as the filter labelled it
  for (const auto& f : tracked_feats) carried.emplace(f.id, f);
  w.out.rejected = w.out.removed.size();
  if (params_.follow_eliminated) followEliminated(w, followed, tracks);

  std::vector<const Track*> with_eliminated;  // into prev_tracks_
  detectNew(frame.left, tracks, w.out, with_eliminated);
  for (const Track* t : with_eliminated) {
    Feature f = featureOf(*t, FeatureLabel::kEliminated);  // its first (previous) frame, as lost_moving
    f.has_right = t->has_right;
    f.xy_right = t->xy_right;
    w.out.lost_moving.push_back(f);
  }
  std::vector<Track> final_tracks = assembleFeatures(w, tracks, carried);
  setVelocities(w.out, dt);
  matchNewAndFollowed(w.out, final_tracks);

  std::swap(prev_pyr_, cur_pyr_);  // keep both pyramids' buffers for the next frame
  if (params_.temporal_gain_compensation) prev_left_ = frame.left;
  prev_tracks_ = std::move(final_tracks);
  prev_t_ns_ = frame.t_ns;
  w.out.filter_ms = w.filter_ms;
  w.out.tracking_ms = msSince(start) - w.filter_ms;
  return std::move(w.out);
}

void FeatureTracker::buildPyramids(const StereoFrame& frame) {
  const cv::Size window(params_.klt_window, params_.klt_window);
  cv::buildOpticalFlowPyramid(frame.left, cur_pyr_, window, params_.klt_max_level);
  // Right pyramid first: tracked features are matched before the filter (it may compare stereo observations).
  has_right_image_ = !frame.right.empty() && cams_.size() >= 2;
  if (has_right_image_) {
    const cv::Mat right = params_.stereo_gain_compensation ? matchBrightness(frame.right, frame.left) : frame.right;
    cv::buildOpticalFlowPyramid(right, right_pyr_, window, params_.klt_max_level);
  }
}

std::vector<FeatureTracker::Track> FeatureTracker::separateFollowed(std::vector<Track>& tracks,
                                                                    std::vector<PrevObs>& prev) const {
  // Eliminated tracks still followed skip the filter and the output (reported as removed).
  std::vector<Track> followed;
  if (followed_.empty()) return followed;
  std::vector<Track> rest;
  std::vector<PrevObs> rest_prev;
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    if (followed_.count(tracks[i].id)) {
      followed.push_back(tracks[i]);
      continue;
    }
    rest.push_back(tracks[i]);
    rest_prev.push_back(prev[i]);
  }
  tracks = std::move(rest);
  prev = std::move(rest_prev);
  return followed;
}

void FeatureTracker::filterTracks(FrameWork& w, std::vector<Track>& list, const std::vector<PrevObs>* prev_obs,
                                  std::vector<Feature>& feats) {
  feats.clear();
  for (const auto& t : list) feats.push_back(featureOf(t));
  if (prev_obs) matchRight(cur_pyr_, feats);  // tracked: right match now; new corners: after the top-up
  if (!w.filter) return;
  const auto t0 = Clock::now();
  std::vector<FilterItem> items(feats.size());
  for (std::size_t i = 0; i < feats.size(); ++i) {
    items[i].feature = &feats[i];
    items[i].tracked = prev_obs != nullptr;
    if (prev_obs) {
      const PrevObs& p = (*prev_obs)[i];
      items[i].prev_uv = p.uv;
      items[i].prev_xy = p.xy;
      items[i].prev_has_right = p.has_right;
      items[i].prev_xy_right = p.xy_right;
    }
  }
  w.filter->apply(w.ctx, items);
  std::vector<Track> kept_tracks;
  std::vector<Feature> kept_feats;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (items[i].remove) {
      Feature r = feats[i];
      r.label = FeatureLabel::kEliminated;
      w.out.removed.push_back(r);
      w.removed_tracks.push_back(list[i]);
    } else {
      kept_tracks.push_back(list[i]);
      kept_feats.push_back(feats[i]);
    }
  }
  list = std::move(kept_tracks);
  feats = std::move(kept_feats);
  w.filter_ms += msSince(t0);
}

void FeatureTracker::followEliminated(FrameWork& w, std::vector<Track>& followed, std::vector<Track>& tracks) {
  // Report the ones followed from earlier frames, then follow the newly removed ones too.
  for (const auto& t : followed) w.out.removed.push_back(featureOf(t, FeatureLabel::kEliminated));
  followed.insert(followed.end(), w.removed_tracks.begin(), w.removed_tracks.end());
  followed_.clear();
  for (const auto& t : followed) followed_.insert(t.id);
  tracks.insert(tracks.end(), followed.begin(), followed.end());  // they occupy their place in detectNew
}

std::vector<FeatureTracker::Track> FeatureTracker::assembleFeatures(
    FrameWork& w, const std::vector<Track>& tracks, const std::unordered_map<std::uint64_t, Feature>& carried) {
  std::vector<Track> fresh;
  for (const auto& t : tracks)
    if (t.length == 1) fresh.push_back(t);
  std::vector<Feature> fresh_feats;
  filterTracks(w, fresh, nullptr, fresh_feats);  // seg may remove new corners on moving objects
  std::unordered_map<std::uint64_t, bool> fresh_kept;
  for (const auto& f : fresh_feats) fresh_kept[f.id] = true;

  std::vector<Track> final_tracks;
  for (const auto& t : tracks) {
    if (t.length == 1) {
      if (!fresh_kept.count(t.id)) continue;
      w.out.features.push_back(featureOf(t));
    } else if (!followed_.count(t.id)) {  // followed tracks are kept, not output
      auto it = carried.find(t.id);
      if (it == carried.end()) continue;
      w.out.features.push_back(it->second);
    }
    final_tracks.push_back(t);
  }
  return final_tracks;
}

void FeatureTracker::setVelocities(FeatureFrame& out, double dt) const {
  if (dt <= 0) return;  // velocities from the previous observation
  std::unordered_map<std::uint64_t, const Track*> prev;
  for (const auto& t : prev_tracks_) prev[t.id] = &t;
  for (auto& f : out.features) {
    auto it = prev.find(f.id);
    if (it == prev.end()) continue;
    const Track& p = *it->second;
    f.velocity_px = (f.uv - toEigen(p.uv)) / dt;
    f.velocity_xy = (f.xy - p.xy) / dt;
    if (f.hasAnyRight() && p.hasAnyRight()) f.velocity_xy_right = (f.xy_right - p.xy_right) / dt;
  }
}

void FeatureTracker::matchNewAndFollowed(FeatureFrame& out, std::vector<Track>& final_tracks) {
  // New corners, and eliminated tracks followed from earlier frames (removed features may
  // go to the dynamic map); tracked features were matched before the filter.
  std::vector<std::size_t> new_idx, followed_idx;
  for (std::size_t i = 0; i < out.features.size(); ++i)
    if (out.features[i].track_length == 1) new_idx.push_back(i);
  for (std::size_t i = out.rejected; i < out.removed.size(); ++i) followed_idx.push_back(i);
  matchRight(cur_pyr_, out.features, &new_idx);
  matchRight(cur_pyr_, out.removed, &followed_idx);
  std::unordered_map<std::uint64_t, const Feature*> by_id;  // this frame's observation of each kept track
  for (const auto& f : out.features) by_id.emplace(f.id, &f);
  for (const auto& f : out.removed) by_id.emplace(f.id, &f);
  for (auto& t : final_tracks) {
    auto it = by_id.find(t.id);
    t.has_right = it != by_id.end() && it->second->has_right;
    t.right_low_zncc = it != by_id.end() && it->second->right_low_zncc;
    const bool right = t.hasAnyRight();
    t.xy_right = right ? it->second->xy_right : Eigen::Vector2d::Zero();
    t.uv_right = right ? it->second->uv_right : Eigen::Vector2d::Zero();
  }
}

cv::Mat drawTracks(const cv::Mat& left, const FeatureFrame& frame) {
  cv::Mat out;
  cv::cvtColor(left, out, cv::COLOR_GRAY2BGR);
  auto color = [](FeatureLabel l) {
    switch (l) {
      case FeatureLabel::kStatic:
        return cv::Scalar(0, 220, 0);
      case FeatureLabel::kCandidate:
        return cv::Scalar(0, 220, 255);
      case FeatureLabel::kEliminated:
      case FeatureLabel::kConfirmedDynamic:
        return cv::Scalar(0, 0, 255);
    }
    return cv::Scalar(255, 255, 255);
  };
  auto draw = [&](const Feature& f) {
    const cv::Point2f p(static_cast<float>(f.uv.x()), static_cast<float>(f.uv.y()));
    const cv::Scalar c = color(f.label);
    if (f.velocity_px.squaredNorm() > 0) {
      const Eigen::Vector2d back = f.uv - f.velocity_px * 0.05;
      cv::line(out, p, cv::Point2f(static_cast<float>(back.x()), static_cast<float>(back.y())), c, 1, cv::LINE_AA);
    }
    cv::circle(out, p, f.label == FeatureLabel::kEliminated ? 4 : 3, c, f.has_right ? cv::FILLED : 1, cv::LINE_AA);
  };
  for (const auto& f : frame.features) draw(f);
  for (const auto& f : frame.removed) draw(f);
  char text[160];
  std::snprintf(text, sizeof(text), "%zu features, %zu removed, %zu new", frame.features.size(), frame.removed.size(),
                frame.detected);
  cv::putText(out, text, cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return out;
}

}  // namespace idyvins::frontend
