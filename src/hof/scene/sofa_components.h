#pragma once
/// @file
/// What SOFA itself would create: the component types of SOFA's factory (its main repository's
/// modules and in-tree plugins, v25.06, with the names older scenes use: 2008 aliases, renamed
/// and removed components), and the data (attributes) of the components HoF reads. SOFA refuses
/// a scene with a type its factory does not know ("Object type X was not created") and warns
/// about attributes no data of the component takes; HoF does the same, naming the closest known
/// names. Internal to the scene module.

#include <cstddef>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace hof::scene::detail {

/// True when SOFA (any version HoF reads: 2008 to v25.06) creates a component of this type.
[[nodiscard]] bool is_known_sofa_component(std::string_view type);

/// Every data name (with aliases, and the base classes' data) a scene may set on `type`, sorted;
/// empty when HoF does not list them for that type (it then does not check attributes).
[[nodiscard]] std::span<const std::string_view> sofa_data_names(std::string_view type);

/// Every known component type, sorted.
[[nodiscard]] std::span<const std::string_view> known_sofa_components();

/// Up to `count` names of `candidates` closest to `name` (case-insensitive edit distance, then
/// alphabetical), among those close enough to be a misspelling (at most a third of the name's
/// letters off, and at least 2).
[[nodiscard]] std::vector<std::string> closest_names(std::string_view name,
                                                     std::span<const std::string_view> candidates,
                                                     std::size_t count = 3);

}  // namespace hof::scene::detail
