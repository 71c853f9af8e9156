// A URDF arm in the closed loop: PinocchioArm (pinocchio_arm.hpp) behind the Arm concept of
// arm_model.hpp, with bounded dynamic sizes (types.hpp), so that ClosedLoop<UrdfLoopArm, Basis>
// runs the paper's laws (eqs. 1-28) on any fixed-base serial arm of up to kMaxDof joints.
//   M, M^-1, C, G, F   PinocchioArm::compute, copied into the loop's bounded Terms
//   ddq                eq. (1): M^-1 (tau - C dq - G - F - tau_d)
// make_loop (any_simulation.hpp) builds the plant and the model of a run from its UrdfArmSettings,
// through a UrdfArmCache (below) that reads each URDF once.
//
// Threads may share an arm (PinocchioArm is immutable; compute() works in the caller's Terms).
#pragma once

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "adparm/pinocchio_arm.hpp"
#include "adparm/settings.hpp"
#include "adparm/types.hpp"

namespace adparm {

class UrdfLoopArm {
 public:
  static constexpr int kDof = Dynamic;
  using Joint = JointVector<Dynamic>;

  // The loop's bounded terms, and Pinocchio's (dynamic) terms that compute() copies into them.
  struct Terms : DynamicTerms {
    PinocchioArm::Terms pinocchio;
  };

  // An arm already read (UrdfArmCache::arm, the bench); errors name `field`. Shares the arm's
  // parsed model.
  explicit UrdfLoopArm(const PinocchioArm& arm, const std::string& field = "") : arm_(arm) {
    if (arm_.dof() > kMaxDof)
      throw std::invalid_argument((field.empty() ? "" : field + ": ") + "the arm has " +
                                  std::to_string(arm_.dof()) + " joints; the core supports 1 to " +
                                  std::to_string(kMaxDof) +
                                  ": lock joints (plant.locked_joints) to move the others");
  }

  // The same arm with the inertias and friction of `estimate` (the online identifier's,
  // urdf_regressor.hpp; made by arm.arm().make_estimate(), owned by the caller and outliving
  // this arm): compute() gives the estimate's terms. No heap allocation.
  UrdfLoopArm(const UrdfLoopArm& arm, const PinocchioArm::EstimateData* estimate)
      : arm_(arm.arm_), estimate_(estimate) {}

  int dof() const { return arm_.dof(); }
  const PinocchioArm& arm() const { return arm_; }

  void init_terms(Terms& terms) const {
    init_dynamic_terms(terms, dof());
    terms.pinocchio = arm_.make_terms();
  }

  // No heap allocation: Pinocchio fills the terms' own buffers, copied into the bounded terms.
  void compute(const Joint& q, const Joint& dq, Terms& terms) const {
    arm_.compute(q, dq, terms.pinocchio, estimate_);
    terms.mass = terms.pinocchio.mass;
    terms.mass_inverse = terms.pinocchio.mass_inverse;
    terms.coriolis = terms.pinocchio.coriolis;
    terms.gravity = terms.pinocchio.gravity;
    terms.friction = terms.pinocchio.friction;
  }

  // eq. (1)
  Joint acceleration(const Terms& terms, const Joint& dq, const Joint& tau,
                     const Joint& tau_d) const {
    return dynamic_acceleration(terms, dq, tau, tau_d);
  }

 private:
  PinocchioArm arm_;
  const PinocchioArm::EstimateData* estimate_ = nullptr;  // none: the arm's own inertias
};

// The URDF arms read for a set of runs (one loop's plant and model; every run of a Batch; the
// binding's loops): each version of a file (its modification time and size) with a set of locked
// joints is parsed once, and the arms of it share that parse (an arm under other gravity or
// friction is PinocchioArm::with_gravity_and_friction of it). A file changed since is read again.
// Holds the kCapacity files read last. Thread-safe: the workers of a Batch share one (the arms
// are immutable; each run has its own Terms).
class UrdfArmCache {
 public:
  static constexpr std::size_t kCapacity = 32;

  // The arm of `settings`; errors name `field` (plant.urdf or model.urdf) or its section's
  // locked_joints. A file that cannot be read is not kept (each asker gets the error).
  UrdfLoopArm arm(const UrdfArmSettings& settings, const std::string& field) {
    if (settings.urdf.empty()) throw std::invalid_argument(field + ": no URDF file given");
    try {
      return UrdfLoopArm(parsed(settings), field);
    } catch (const LockedJointsError& error) {  // names field's section: plant.locked_joints
      throw std::invalid_argument(error.with_section(field.substr(0, field.find('.'))));
    } catch (const std::invalid_argument& error) {
      const std::string message = error.what();
      if (message.rfind(field + ": ", 0) == 0) throw;
      throw std::invalid_argument(field + ": " + message);
    }
  }

 private:
  // A version of a file: its modification time and size; none if the file cannot be stat'ed
  // (the parse then names the problem).
  struct Version {
    std::filesystem::file_time_type modified{};
    std::uintmax_t size = 0;
    bool operator==(const Version& other) const {
      return modified == other.modified && size == other.size;
    }
  };
  static bool version(const std::string& path, Version& out) {
    std::error_code error;
    out.modified = std::filesystem::last_write_time(path, error);
    if (error) return false;
    out.size = std::filesystem::file_size(path, error);
    return !error;
  }

  struct Entry {
    std::string urdf;
    LockedJoints locked_joints;
    Version version;
    PinocchioArm arm;
  };

  // The arm of `settings`: the parse below, its inertia scaled (UrdfArmSettings::inertia_scale).
  PinocchioArm parsed(const UrdfArmSettings& settings) {
    return unscaled(settings).with_inertia_scaled(settings.inertia_scale);
  }

  PinocchioArm unscaled(const UrdfArmSettings& settings) {
    const auto read = [&] {
      return PinocchioArm(settings.urdf, settings.gravity, settings.coulomb, settings.viscous,
                          settings.locked_joints);
    };
    Version now;
    if (!version(settings.urdf, now)) return read();
    std::lock_guard<std::mutex> lock(mutex_);  // held while parsing: one parse per file
    for (const Entry& entry : entries_)
      if (entry.urdf == settings.urdf && entry.locked_joints == settings.locked_joints &&
          entry.version == now)
        return entry.arm.with_gravity_and_friction(settings.gravity, settings.coulomb,
                                                   settings.viscous);
    PinocchioArm arm = read();
    if (entries_.size() == kCapacity) entries_.erase(entries_.begin());
    entries_.push_back({settings.urdf, settings.locked_joints, now, arm});
    return arm;
  }

  std::mutex mutex_;
  std::vector<Entry> entries_;  // oldest first
};

}  // namespace adparm

// The URDF arm's Regressor for the online identifier and its IdentifierOf entry (after
// UrdfLoopArm, which it needs).
#include "adparm/urdf_regressor.hpp"
