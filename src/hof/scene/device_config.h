#pragma once
/// @file
/// Device specs as users type them (`scripted:poke,start=0;0;0.05`, `replay:FILE.csv,loop`,
/// `udp:HOST:PORT`, `mouse`, `dhd,index=1`, ... — docs/device-protocol.md, "Spec strings")
/// become a typed haptics::DeviceConfig here: below scene/, a device is chosen by type, not by
/// name.
///
///   replay:PATH.csv[,loop]                       recorded trajectory (docs/device-protocol.md)
///   scripted:poke[,key=value...]                 built-in motions: poke, press-and-slide, palpate, circle, hold
///   virtual-hand:MOTION[,key=value...]           compliant hand following a scripted motion
///   udp:[HOST:]PORT[,timeout=S]                  datagram bridge (docs/device-protocol.md)
///   spacemouse[,scale=M]                         3Dconnexion SpaceMouse via spacenavd (input only)
///   mouse                                        the window's cursor (hof gui; input only)
///   dhd[,index=N][,library=PATH]                 a Force Dimension device (libdhd, loaded at run time)
///   openhaptics[,device=NAME][,library=PATH]     a 3D Systems Touch / Phantom (OpenHaptics' libHD)
/// Every backend also takes model=virtual|falcon|omni|touch (device_spec_for_model; for udp,
/// a hello packet received within hello_wait=S overrides it).
///
///   SPEC    := BACKEND [':' ARGUMENT] (',' OPTION)*
///   OPTION  := KEY ['=' VALUE]          (a bare KEY is a flag)
///   VECTOR  := NUMBER ';' NUMBER ';' NUMBER

#include <memory>
#include <string_view>

#include "hof/core/error.h"
#include "hof/haptics/device_config.h"

namespace hof::scene {

/// The typed configuration of `spec`. Every error starts with "device spec 'SPEC': " and says
/// what is wrong (unknown backend, motion or key, a key given twice, a bad value, a missing
/// file or port, an unknown model, an unreadable UDP key file).
[[nodiscard]] Expected<haptics::DeviceConfig> parse_device_spec(std::string_view spec);

/// The figures of a model by its name (haptics::device_spec_for_model): virtual, falcon, omni,
/// touch; kInvalidArgument for any other name.
[[nodiscard]] Expected<haptics::DeviceSpec> device_spec_for_model(std::string_view model);

/// parse_device_spec + haptics::open_device. Errors when opening name the spec too, except a
/// replay file's (which names the file and line) and the SpaceMouse's (spnav's own message).
[[nodiscard]] Expected<std::unique_ptr<haptics::Device>> open_device(std::string_view spec);

}  // namespace hof::scene
