#pragma once
// Stereo KLT feature tracker (VINS-Fusion's front end, rewritten): left(k-1) ->
// left(k) pyramidal KLT with an optional forward-backward check, border check,
// rejection filter, min-distance mask favouring long tracks, Shi-Tomasi top-up,
// left -> right KLT with the same back check and an epipolar check, undistortion.

#include <memory>
#include <opencv2/core/mat.hpp>
#include <opencv2/imgproc.hpp>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "camera/camera_model.h"
#include "camera/rig.h"
#include "core/measurements.h"
#include "frontend/feature_filter.h"
#include "frontend/feature_frame.h"
#include "frontend/patch_alignment.h"
#include "frontend/tracker_params.h"

namespace idyvins::frontend {

/// Tracks features across stereo frames; one instance per sequence.
class FeatureTracker {
 public:
  FeatureTracker(const camera::Rig& rig, const TrackerParams& params);

  /// Processes the next stereo frame. `filter` may be null (baseline), `mask` is the
  /// left image's ground-truth object-id mask (seg mode) or null.
  FeatureFrame track(const StereoFrame& frame, const MotionPrior& prior, FeatureFilter* filter,
                     const cv::Mat* mask = nullptr);

  /// Drops every track (after a reset of the estimator, for example).
  void reset();

 private:
  struct Track {
    std::uint64_t id;
    cv::Point2f uv;
    Eigen::Vector2d xy;
    int length;
    std::shared_ptr<const PatchTemplate> patch;             ///< first appearance (null: not aligned)
    Eigen::Matrix2d A_patch = Eigen::Matrix2d::Identity();  ///< current affine shape of the patch
    bool has_right = false;                                 ///< right match in this track's frame
    bool right_low_zncc = false;                            ///< Feature::right_low_zncc
    bool hasAnyRight() const { return has_right || right_low_zncc; }
    Eigen::Vector2d xy_right = Eigen::Vector2d::Zero();
    Eigen::Vector2d uv_right = Eigen::Vector2d::Zero();
    Eigen::Vector2d flow = Eigen::Vector2d::Zero();  ///< displacement since the previous frame (px)
  };
  /// A track's observation in the previous frame.
  struct PrevObs {
    Eigen::Vector2d uv, xy;
    bool has_right;
    Eigen::Vector2d xy_right;
    Eigen::Vector2d uv_right;
  };
  /// What one call of track() builds up while it runs.
  struct FrameWork {
    FeatureFrame out;
    FeatureFilter* filter;
    FilterContext ctx;
    std::vector<Track> removed_tracks;  ///< tracks behind out.removed (this frame's removals), same order
    double filter_ms;                   ///< filter and lost-corner time so far
  };
  static Feature featureOf(const Track& t, FeatureLabel label = FeatureLabel::kStatic);
  void buildPyramids(const StereoFrame& frame);
  /// Takes the eliminated tracks still followed out of `tracks` (and `prev`) and returns them.
  std::vector<Track> separateFollowed(std::vector<Track>& tracks, std::vector<PrevObs>& prev) const;
  /// Features of `list` through the filter; removed ones go to w.out.removed. With
  /// `prev_obs` (tracked features) they are matched in the right image first.
  void filterTracks(FrameWork& w, std::vector<Track>& list, const std::vector<PrevObs>* prev_obs,
                    std::vector<Feature>& feats);
  /// follow_eliminated: reports the followed tracks and follows this frame's removals.
  void followEliminated(FrameWork& w, std::vector<Track>& followed, std::vector<Track>& tracks);
  /// Filters the new corners, fills w.out.features, returns the tracks kept for the next frame.
  std::vector<Track> assembleFeatures(FrameWork& w, const std::vector<Track>& tracks,
                                      const std::unordered_map<std::uint64_t, Feature>& carried);
  void setVelocities(FeatureFrame& out, double dt) const;
  /// Right matches of new corners and followed tracks; records each kept track's match.
  void matchNewAndFollowed(FeatureFrame& out, std::vector<Track>& final_tracks);
  /// KLT of prev_tracks_ into `pyr`: the continued tracks, their previous observations, the
  /// lost ones (into prev_tracks_), and why each was lost (out.lost_tracks, out.lost_new).
  void trackPrevious(const std::vector<cv::Mat>& pyr, const cv::Mat& image, std::vector<Track>& tracks,
                     std::vector<PrevObs>& prev, std::vector<const Track*>& lost, FeatureFrame& out);
  /// After KLT's checks passed at `p1`: the first-patch alignment, the border and the camera.
  /// Null when the track goes on (p1, A_patch and xy set), else why it ends.
  std::size_t TrackLosses::*continueTrack(const Track& old, const cv::Mat& image, cv::Point2f& p1,
                                          Eigen::Matrix2d& A_patch, Eigen::Vector2d& xy) const;
  /// lost_track_test: hands the lost one-frame tracks with a right match to the
  /// filter's judgement (with the tracker's measurements, Probe) and reports those judged
  /// moving in w.out.lost_moving.
  void judgeLost(const cv::Mat& image, const std::vector<const Track*>& lost, FrameWork& w) const;
  class Probe;
  /// Pyramidal KLT on all levels from p0 in `from` to `to`, started at p1 (updated); the status.
  std::vector<uchar> kltFromGuess(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                  const std::vector<cv::Point2f>& p0, std::vector<cv::Point2f>& p1) const;
  /// Whether a kept followed eliminated track within `radius` px moved with `t`
  /// (displacements within TrackerParams::move_with_eliminated_px).
  bool movesWithEliminated(const Track& t, const std::vector<Track>& kept, int radius) const;
  /// Prunes tracks closer than min_dist to a longer one, then detects new corners. A
  /// corner in its second frame pruned next to a followed eliminated track that moved
  /// with it is appended to `with_eliminated` (its previous-frame track, in prev_tracks_).
  /// Sets out.detected and counts the pruned tracks in out.lost_tracks / lost_new.
  void detectNew(const cv::Mat& image, std::vector<Track>& tracks, FeatureFrame& out,
                 std::vector<const Track*>& with_eliminated);
  /// Matches features[i] for i in `which` (all when null) in the right image: KLT from the
  /// left position on klt_max_level + 1 levels, backward check, epipolar and ZNCC checks.
  void matchRight(const std::vector<cv::Mat>& left_pyr, std::vector<Feature>& features,
                  const std::vector<std::size_t>* which = nullptr);
  /// stereo_refine: moves `uv_right` to where the left patch at `uv` aligns in the right
  /// image (full resolution), when that converges within 1 px of it.
  void refineRight(const cv::Mat& left, const Eigen::Vector2d& uv, cv::Point2f& uv_right) const;
  bool inBorder(const cv::Point2f& p) const;  ///< border_px inside the image and inside lens_mask_
  AlignOptions alignOptions() const;          ///< first-patch alignment with params_.patch_min_inside

  int image_width_ = 0, image_height_ = 0;
  TrackerParams params_;
  cv::Ptr<cv::CLAHE> clahe_;  ///< params_.equalize
  std::vector<std::unique_ptr<camera::CameraModel>> cams_;
  Eigen::Matrix3d E_c1_c0_;  ///< essential matrix: x1ᵀ E x0 = 0
  Eigen::Isometry3d T_c1_c0_ = Eigen::Isometry3d::Identity();
  std::vector<cv::Mat> prev_pyr_, cur_pyr_, right_pyr_;  ///< reused across frames (no per-frame allocation)
  std::vector<cv::Mat>
      matched_pyr_;               ///< temporal_gain_compensation: the current image at the previous one's brightness
  cv::Mat prev_left_;             ///< temporal_gain_compensation: the previous left image
  bool has_right_image_ = false;  ///< right_pyr_ holds the current frame's right image
  cv::Mat detect_mask_;
  cv::Mat lens_mask_;  ///< lensMask of the left camera (empty: the whole image images the front)
  std::vector<Track> prev_tracks_;
  std::unordered_set<std::uint64_t> followed_;  ///< eliminated tracks still followed (follow_eliminated)
  TimeNs prev_t_ns_ = 0;
  std::uint64_t next_id_ = 0;
};

/// Draws the frame's features colored by label (green static, yellow candidate,
/// red eliminated) with their flow from the previous frame, like the paper's Fig. 4.
cv::Mat drawTracks(const cv::Mat& left, const FeatureFrame& frame);

}  // namespace idyvins::frontend
