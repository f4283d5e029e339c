#include "hof/scene/device_config.h"

namespace hof::scene {

// The parser itself is still haptics::parse_device_spec while coupling's SetDevice opens spec
// strings (coupling sits below scene/); it moves here when SetDevice carries a DeviceConfig.
Expected<haptics::DeviceConfig> parse_device_spec(std::string_view spec) { return haptics::parse_device_spec(spec); }

Expected<std::unique_ptr<haptics::Device>> open_device(std::string_view spec) { return haptics::open_device(spec); }

}  // namespace hof::scene
