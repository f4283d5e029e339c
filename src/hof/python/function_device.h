#pragma once
// A Python function as the haptic device (hof.World.run(device=f)).

#include <string_view>

#include "hof/coupling/session.h"
#include "hof/haptics/device.h"
#include "hof/python/common.h"

namespace hof::python {

// A Python function t -> (x, y, z) as a device (virtual time only: it is called on the
// caller's thread with the GIL taken again). Positions are in the world frame, metres; the
// velocity is the difference of the last two positions. An exception, a NaN or a value that
// is not three numbers ends the run: the device reports no reading from then on (the force
// fades to zero) and the run raises the error.
class FunctionDevice final : public haptics::Device {
 public:
  FunctionDevice(py::function function, PendingPythonError& error, coupling::Session*& session)
      : function_(std::move(function)), error_(error), session_(session) {}
  ~FunctionDevice() override {
    py::gil_scoped_acquire gil;
    function_ = py::function();
  }
  [[nodiscard]] const haptics::DeviceSpec& spec() const override { return spec_; }
  [[nodiscard]] std::string_view backend() const override { return "python-function"; }
  haptics::DeviceReading read(double time_s) override {
    haptics::DeviceReading r;
    r.time_s = time_s;
    if (failed_) return r;
    py::gil_scoped_acquire gil;
    try {
      const py::object value = function_(time_s);
      const auto numbers = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
      if (!numbers || numbers.size() != 3) {
        throw py::value_error(fmt::format("the device function must return a position (x, y, z) in metres, got {}",
                                          py::repr(value).cast<std::string>()));
      }
      r.position_m = Vec3(numbers.data()[0], numbers.data()[1], numbers.data()[2]);
      if (!r.position_m.allFinite()) {
        throw py::value_error(fmt::format("the device function returned {} at t = {} s: not finite",
                                          py::repr(value).cast<std::string>(), time_s));
      }
    } catch (py::error_already_set& e) {
      e.restore();
      fail();
      return r;
    } catch (py::builtin_exception& e) {
      e.set_error();
      fail();
      return r;
    }
    r.velocity_m_per_s =
        has_last_ && time_s > last_time_ ? Vec3((r.position_m - last_) / (time_s - last_time_)) : Vec3::Zero();
    last_ = r.position_m;
    last_time_ = time_s;
    has_last_ = true;
    r.valid = true;
    return r;
  }
  void write_force(const Vec3&, const Vec3&) override {}
  [[nodiscard]] haptics::DeviceHealth health() const override {
    return failed_ ? haptics::DeviceHealth::kFailed : haptics::DeviceHealth::kOk;
  }

 private:
  void fail() {
    error_.fetch();
    failed_ = true;
    if (session_) session_->request_stop();
  }
  py::function function_;
  PendingPythonError& error_;
  coupling::Session*& session_;
  haptics::DeviceSpec spec_;
  Vec3 last_{Vec3::Zero()};
  double last_time_{0.0};
  bool has_last_{false};
  bool failed_{false};
};

}  // namespace hof::python
