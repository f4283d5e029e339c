#pragma once
/// @file
/// A shared library opened at run time (dlopen), for software HoF does not link against: the
/// haptic device vendors' SDKs, which are not Debian packages and may not be on the machine.
/// Opening one that is not there, or one that lacks a function, is a clear error naming the
/// file names tried, where the system looked, and the symbol — never a crash.

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "hof/core/error.h"

namespace hof {

class SharedLibrary {
 public:
  /// Opens the first of `names` the dynamic loader finds. A name with a '/' is a path; a bare
  /// name is looked for as dlopen does (LD_LIBRARY_PATH, the loader's cache, /lib and
  /// /usr/lib). `what` names the software in errors ("the Force Dimension SDK"), `install`
  /// says how to get it. The error lists every name tried with the loader's reason and the
  /// search path.
  static Expected<SharedLibrary> open(std::span<const std::string> names, std::string_view what,
                                      std::string_view install);

  SharedLibrary(SharedLibrary&&) noexcept = default;
  SharedLibrary& operator=(SharedLibrary&&) noexcept = default;
  ~SharedLibrary() = default;

  /// The address of a function: the error names the library file and the symbol.
  template <class Function>
  Expected<Function*> function(const char* symbol) const {
    auto address = lookup(symbol);
    if (!address) return std::unexpected(address.error());
    return reinterpret_cast<Function*>(*address);
  }

  /// Sets `slot` to the function `symbol` (the error names the library file and the symbol).
  template <class Function>
  Expected<void> bind(const char* symbol, Function*& slot) const {
    auto f = function<Function>(symbol);
    if (!f) return std::unexpected(f.error());
    slot = *f;
    return {};
  }
  /// Sets `slot` to the function `symbol`, or null when the library has none (an optional one).
  template <class Function>
  void bind_optional(const char* symbol, Function*& slot) const {
    auto f = function<Function>(symbol);
    slot = f ? *f : nullptr;
  }

  /// The file that was opened (as the loader resolved it).
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  struct Closer {
    void operator()(void* handle) const;
  };
  SharedLibrary(void* handle, std::string path) : handle_(handle), path_(std::move(path)) {}
  [[nodiscard]] Expected<void*> lookup(const char* symbol) const;

  std::unique_ptr<void, Closer> handle_;
  std::string path_;
};

}  // namespace hof
