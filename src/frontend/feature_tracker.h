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
#include "core/measurements.h"
#include "frontend/feature_filter.h"
#include "frontend/feature_frame.h"
#include "frontend/patch_alignment.h"
#include "io/config.h"

namespace idyvins::frontend {

/// Tracker options beyond the config's tracker block.
struct TrackerParams {
  int klt_window = 13;  ///< px; smaller than VINS-Fusion's 21: less drift under perspective change (measured)
  /// Pyramid levels above the full image (OpenCV's maxLevel: 4 gives five images); with the
  /// 13 px window the capture range is about VINS-Fusion's 21 px window on 3 levels.
  int klt_levels = 4;
  /// Pyramid levels of the backward checks: they start at the forward start point, so a
  /// narrow basin suffices (VINS-Fusion uses 1 for its reverse check).
  int klt_back_levels = 1;
  int klt_iterations = 30;     ///< KLT stops after this many iterations ...
  double klt_epsilon = 0.01;   ///< ... or when the update is below this (px)
  double flow_back_px = 0.5;       ///< max forward-backward distance
  /// A right match whose patch correlates worse than this with the left one (ZNCC of the
  /// patch_half patches) is dropped: such matches are more often wrong (> 1 px or hidden)
  /// or beside a vehicle than the rest (docs/method.md). -1 switches the check off.
  double stereo_min_zncc = 0.8;
  int border_px = 1;
  /// Keep following features the filter eliminated (IDY modes): they are reported in
  /// FeatureFrame::removed every frame and never output as features again, but they
  /// keep their place in the image so that no new corner is seeded on the same moving
  /// object (a fresh corner there would enter the estimator unscored for a frame).
  bool keep_following_eliminated = false;
  /// Judge the new corners lost in their second frame (IDY modes; extension of
  /// DESIGN §4.3): a corner with a right match is moved as a static point by the motion
  /// prior and its first patch aligned there; when it is not found where a static point
  /// would be, it is reported in FeatureFrame::lost_moving. Such a corner never reaches
  /// the estimator's optimization (one observation), so this labels, it does not filter.
  bool judge_lost_new_tracks = false;
  double lost_stereo_sigma_px = 0.25;  ///< per-coordinate match noise behind the depth tolerance
  double lost_base_tolerance_px = 2.0; ///< tolerance on top of the depth and prior terms
  /// Not judged when the stereo depth measured at the predicted pixel is below this ratio
  /// of the predicted depth (the corner is hidden behind something nearer).
  double lost_occlusion_ratio = 0.8;
  /// Judged moved only when the best ZNCC of the first patch near the prediction is below this.
  double lost_max_zncc = 0.5;
  /// After KLT, align each track's first-appearance patch (affine, gain/bias invariant)
  /// to the new image and move the feature there: removes KLT's frame-to-frame drift.
  /// Tracks whose patch no longer matches are dropped (slid along an edge, occluded,
  /// on a depth discontinuity).
  bool align_first_patch = true;
  int patch_half = 7;                 ///< template of (2 half + 1)² px
  double min_patch_zncc = 0.8;        ///< below: the track is dropped
  double max_patch_correction_px = 2.0;  ///< KLT and alignment disagree by more: dropped
  /// With align_first_patch, no corner is detected within this many px of the image border. The default,
  /// patch_half + 2, keeps every first patch whole: a corner nearer the border used to
  /// have no first patch and followed KLT alone, drifting 0.3-0.5 px per frame (and the
  /// detector's gradients reflect at the border, so an edge meeting it looks like a
  /// corner). Values and measurements: docs/method.md ("Corners at the border").
  int corner_margin_px = 9;
  /// Share of a first patch that must lie in the image (AlignOptions::min_inside). 1: the
  /// whole patch (a track is dropped when its patch reaches the border; stereo ZNCC needs
  /// both patches whole). Below 1: corners nearer the border than patch_half keep the part
  /// of their patch in the image, tracks keep aligning on the pixels in the image until
  /// less than this share remains, and the stereo ZNCC uses the offsets inside both images.
  /// Measured with corner_margin_px 2 on the standard and validation suites, and left at 1
  /// (docs/method.md).
  double patch_min_inside = 1.0;
  /// With judge_lost_new_tracks and keep_following_eliminated (IDY modes): a corner in
  /// its second frame that the min_dist pruning drops next to a followed eliminated
  /// track, and whose displacement since its first frame agrees with that track's within
  /// this many px, is judged moving with it (reported in FeatureFrame::lost_moving, like a
  /// lost corner judged moving). Such corners appear where a receding vehicle shrinks in
  /// the image (measured values in docs/method.md). 0 switches it off.
  double move_with_eliminated_px = 6.0;
};

/// `image` with its brightness mapped to `reference`'s: I' = a I + b with a and b such that
/// the mean and standard deviation equal the reference's (8-bit, saturated). Returns
/// `image` itself (no copy) when the standard deviations and the means already agree
/// within `tolerance` (relative).
cv::Mat matchBrightness(const cv::Mat& image, const cv::Mat& reference, double tolerance = 0.01);

/// Tracks features across stereo frames; one instance per sequence.
class FeatureTracker {
 public:
  explicit FeatureTracker(const Config& config, const TrackerParams& params = {});

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
    std::shared_ptr<const PatchTemplate> patch;  ///< first appearance (null: not aligned)
    Eigen::Matrix2d A_patch = Eigen::Matrix2d::Identity();  ///< current affine shape of the patch
    bool has_right = false;                                 ///< right match in this track's frame
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
  /// keep_following_eliminated: reports the followed tracks and follows this frame's removals.
  void followEliminated(FrameWork& w, std::vector<Track>& followed, std::vector<Track>& tracks);
  /// Filters the new corners, fills w.out.features, returns the tracks kept for the next frame.
  std::vector<Track> assembleFeatures(FrameWork& w, const std::vector<Track>& tracks,
                                      const std::unordered_map<std::uint64_t, Feature>& carried);
  void setVelocities(FeatureFrame& out, double dt) const;
  /// Right matches of new corners and followed tracks; records each kept track's match.
  void matchNewAndFollowed(FeatureFrame& out, std::vector<Track>& final_tracks);
  void trackPrevious(const std::vector<cv::Mat>& pyr, const cv::Mat& image, std::vector<Track>& tracks,
                     std::vector<PrevObs>& prev, std::vector<const Track*>& lost);
  /// Where the prior puts a track's previous-frame stereo point as static (uv_pred) and how
  /// far from there it may be found (tol_px); false when it cannot be said.
  bool predictStatic(const Track& t, const MotionPrior& prior, Eigen::Vector3d& p_pred, Eigen::Vector2d& uv_pred,
                     double& tol_px) const;
  /// judge_lost_new_tracks: reports in out.lost_moving the lost one-frame tracks that are not
  /// found (KLT from the prediction, then the first patch) near their static prediction.
  void judgeLost(const std::vector<cv::Mat>& pyr, const cv::Mat& image, const MotionPrior& prior,
                 const std::vector<const Track*>& lost, FeatureFrame& out) const;
  /// A lost new corner the static hypothesis can be tested on, with its prediction.
  struct LostJudged {
    const Track* track;
    Eigen::Vector3d p_pred;   ///< the static point in the current left camera
    Eigen::Vector2d uv_pred;  ///< its pixel
    double tol_px;
  };
  /// Pyramidal KLT on all levels from p0 in `from` to `to`, started at p1 (updated); the status.
  std::vector<uchar> kltFromGuess(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                  const std::vector<cv::Point2f>& p0, std::vector<cv::Point2f>& p1) const;
  /// Indices of the judged corners neither KLT nor the first patch finds near the prediction.
  std::vector<std::size_t> notFoundNearPrediction(const std::vector<cv::Mat>& pyr, const cv::Mat& image,
                                                  const std::vector<LostJudged>& judged) const;
  /// Per not-found corner: 1 when a clearly nearer surface stands at its predicted pixel.
  std::vector<uchar> hiddenAtPrediction(const std::vector<cv::Mat>& pyr, const std::vector<LostJudged>& judged,
                                        const std::vector<std::size_t>& not_found) const;
  /// Whether a kept followed eliminated track within `radius` px moved with `t`
  /// (displacements within TrackerParams::move_with_eliminated_px).
  bool movesWithEliminated(const Track& t, const std::vector<Track>& kept, int radius) const;
  /// Prunes tracks closer than min_dist to a longer one, then detects new corners. A
  /// corner in its second frame pruned next to a followed eliminated track that moved
  /// with it is appended to `with_eliminated` (its previous-frame track, in prev_tracks_).
  void detectNew(const cv::Mat& image, std::vector<Track>& tracks, std::size_t& detected,
                 std::vector<const Track*>& with_eliminated);
  /// Matches features[i] for i in `which` (all when null) in the right image: KLT from the
  /// left position on klt_levels levels, backward check, epipolar and ZNCC checks.
  void matchRight(const std::vector<cv::Mat>& left_pyr, std::vector<Feature>& features,
                  const std::vector<std::size_t>* which = nullptr);
  bool inBorder(const cv::Point2f& p) const;
  AlignOptions alignOptions() const;  ///< first-patch alignment with params_.patch_min_inside

  Config config_;
  TrackerParams params_;
  cv::Ptr<cv::CLAHE> clahe_;  ///< config.tracker.equalize
  std::vector<std::unique_ptr<camera::CameraModel>> cams_;
  Eigen::Matrix3d E_c1_c0_;  ///< essential matrix: x1ᵀ E x0 = 0
  Eigen::Isometry3d T_c1_c0_ = Eigen::Isometry3d::Identity();
  std::vector<cv::Mat> prev_pyr_, cur_pyr_, right_pyr_;  ///< reused across frames (no per-frame allocation)
  bool has_right_image_ = false;  ///< right_pyr_ holds the current frame's right image
  cv::Mat detect_mask_;
  std::vector<Track> prev_tracks_;
  std::unordered_set<std::uint64_t> followed_;  ///< eliminated tracks still followed (keep_following_eliminated)
  TimeNs prev_t_ns_ = 0;
  std::uint64_t next_id_ = 0;
};

/// Draws the frame's features colored by label (green static, yellow candidate,
/// red eliminated) with their flow from the previous frame, like the paper's Fig. 4.
cv::Mat drawTracks(const cv::Mat& left, const FeatureFrame& frame);

}  // namespace idyvins::frontend
