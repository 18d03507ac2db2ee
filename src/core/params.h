#pragma once
// Declared parameters. Each module's parameter struct lists its config keys once (name,
// unit, rule) in a `declareParams` member; the config reader, printer and writer
// (config/config.h) are visitors of that list, so a key cannot be read without being printed
// and saved, and its default lives only in the struct's member initializer.

#include <string>

namespace idyvins {

/// What a value read from a config must satisfy.
enum class ParamRule {
  kAny,            ///< any finite number
  kPositive,       ///< > 0
  kNonNegative,    ///< >= 0
  kOpenUnit,       ///< in (0, 1)
  kFraction,       ///< in (0, 1]
  kCorrelation,    ///< in [-1, 1]
  kImuNoise,       ///< in (0, 10]: an IMU noise density or random walk (SI units) that can be real
  kGravity,        ///< in [9, 10.5] m/s^2: a gravity magnitude on Earth
  kTimeOffset,     ///< in [-0.5, 0.5] s: a camera-IMU time offset (a larger one is a unit error)
  kExtrinsicMode,  ///< 0, 1 or 2 (VINS-Fusion's estimate_extrinsic)
};

/// One config key.
struct ParamKey {
  const char* name;
  const char* unit = "";  ///< unit and meaning, for listings and docs/cli.md
  ParamRule rule = ParamRule::kAny;
  bool required = false;  ///< VINS-Fusion's keys that every config of its format carries
};

/// Visits a module's parameters: loading, printing and saving implement it.
class ParamVisitor {
 public:
  virtual ~ParamVisitor() = default;
  /// Starts a group of keys (a comment line in saved configs and listings).
  virtual void section(const char* title) = 0;
  virtual void param(const ParamKey& key, double& value) = 0;
  virtual void param(const ParamKey& key, int& value) = 0;
  virtual void param(const ParamKey& key, bool& value) = 0;  ///< 0 or 1 in the file
  virtual void param(const ParamKey& key, std::string& value) = 0;
};

}  // namespace idyvins
