#include "hof/core/shared_library.h"

#include <dlfcn.h>
#include <link.h>

#include <cstdlib>

namespace hof {

namespace {

// Where dlopen looks for a bare name, said the way a user can check it.
std::string search_path() {
  const char* env = std::getenv("LD_LIBRARY_PATH");
  std::string where = env && *env ? "LD_LIBRARY_PATH=" + std::string(env) + ", " : "LD_LIBRARY_PATH unset, ";
  return where + "the loader cache (ldconfig -p), /lib and /usr/lib";
}

}  // namespace

void SharedLibrary::Closer::operator()(void* handle) const {
  if (handle) ::dlclose(handle);
}

Expected<SharedLibrary> SharedLibrary::open(std::span<const std::string> names, std::string_view what,
                                            std::string_view install) {
  std::string tried;
  for (const std::string& name : names) {
    // RTLD_NOW: a library that needs a symbol its own dependencies lack fails here, with the
    // loader's reason, rather than at the first call in the haptic loop. RTLD_LOCAL: its
    // symbols do not leak into the next library opened.
    void* handle = ::dlopen(name.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle) {
      std::string path = name;
      link_map* map = nullptr;
      if (::dlinfo(handle, RTLD_DI_LINKMAP, &map) == 0 && map && map->l_name && *map->l_name) path = map->l_name;
      return SharedLibrary(handle, std::move(path));
    }
    // dlerror() starts with the name it was given: said once.
    const char* raw = ::dlerror();  // (a second call would return null)
    std::string reason = raw ? raw : "";
    if (reason.starts_with(name + ": ")) reason.erase(0, name.size() + 2);
    tried += (tried.empty() ? "" : "; ") + name + " (" + (reason.empty() ? std::string("not found") : reason) + ")";
  }
  return make_error(ErrorCode::kIo, std::string(what) + " is not installed or not found (tried " + tried +
                                        "; searched " + search_path() + "). " + std::string(install));
}

Expected<void*> SharedLibrary::lookup(const char* symbol) const {
  ::dlerror();
  void* address = ::dlsym(handle_.get(), symbol);
  if (!address) {
    return make_error(ErrorCode::kUnsupported,
                      std::string("the library has no function '") + symbol + "' (an SDK version HoF does not know?)",
                      path_);
  }
  return address;
}

}  // namespace hof
