#pragma once
/// @file
/// The window's scripts (`hof gui FILE --script ACTIONS.txt`): one action per line, for tests,
/// demonstrations and the documentation's screenshots. Blank lines and lines starting with
/// '#' are skipped.
///
///   wait SECONDS                 wall time, the window running (animating or not)
///   animate on|off               run or pause the simulation
///   step [N]                     N simulation steps while paused (default 1)
///   reset                        bodies back to rest
///   set ELEMENT@ATTRIBUTE VALUE  a setting by the project file's names:
///                                  haptics/surface@stiffness 0.4, haptics@renderer GodObjectRenderer,
///                                  graphics@renderMode wireframe, mechanics/BODY/COMPONENT@PARAMETER 8000
///   replace mechanics/BODY/COMPONENT TYPE [KEY=VALUE ...]
///                                the component becomes another SOFA type (the scene tree's
///                                switch): replace mechanics/Liver/FEM TetrahedronHyperelasticityFEMForceField
///                                materialName=NeoHookean "ParameterSet=1862 18000"
///   add mechanics/BODY TYPE NAME [KEY=VALUE ...]   a component added to the body's node
///   remove mechanics/BODY/COMPONENT                a component removed
///   region BODY sphere X Y Z RADIUS YOUNGMODULUS   a material region (box: X0 Y0 Z0 X1 Y1 Z1 E);
///   region clear                                    every region removed
///   needle on|off                mount the needle stylus (Haptics > Needle) or take it off;
///                                its settings: set haptics/needle/tissue@capsule 0.03
///   tool point|needle            the stylus's tool (the Tool panel): the point proxy, the needle,
///   tool sphere RADIUS             a sphere, a capsule (its shaft's length, then its radius, m)
///   tool capsule LENGTH RADIUS     or a closed mesh (OBJ/STL; RADIUS: its spheres', default
///   tool mesh FILE [RADIUS]        automatic)
///   rotate X Y Z DEGREES         turns the mouse stylus's tool about the world axis (X, Y, Z)
///   contacts on|off              the contacts' debug view (points and force arrows)
///   pair BODY BODY on|off        contact between two bodies switched on or off (Contacts panel)
///   mouse X Y [DEPTH]            the mouse stylus under window pixel (X, Y), DEPTH metres
///                                beyond the touch plane (default 0)
///   open FILE                    as File > Open: a file that does not load shows its error and
///                                leaves the world as it was (the script goes on)
///   show PANEL                   opens a panel: tool, contacts, needle, mechanics, haptics,
///                                graphics, messages
///   record FILE.csv | off        start recording the stylus (replay format), or stop and write it
///   screenshot FILE.png          the window as it is drawn
///   save FILE.hof                the project with every change made so far
///   quit                         close the window (the script's end does too)

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "hof/core/error.h"

namespace hof::app {

struct ScriptAction {
  enum class Kind {
    kWait,
    kAnimate,
    kNeedle,
    kTool,
    kRotate,
    kContacts,
    kPair,
    kStep,
    kReset,
    kSet,
    kEdit,
    kRegion,
    kMouse,
    kShow,
    kOpen,
    kRecord,
    kScreenshot,
    kSave,
    kQuit
  };
  Kind kind{Kind::kWait};
  int line{0};
  double number{0.0};         ///< wait: seconds; step: steps; mouse: x
  double y{0.0}, depth{0.0};  ///< mouse
  bool on{false};             ///< animate; record (false: stop); contacts; pair
  /// set; edit: element = the path, value = replace|add|remove; pair: element, attribute = the bodies
  std::string element, attribute, value;
  std::string type, name;  ///< edit: the new component's type and (add) name; tool: type = the kind
  std::vector<std::pair<std::string, std::string>> attributes;  ///< edit: KEY=VALUE
  /// region: centre and radius, or corners; then E (empty: clear); tool: radius, or length and
  /// radius; rotate: the axis and the angle (degrees)
  std::vector<double> numbers;
  bool box{false};             ///< region
  std::filesystem::path file;  ///< screenshot, save, record; tool: the mesh
  std::string text;            ///< the line as written
};

/// Reads and checks a script. Errors name the file and line.
[[nodiscard]] Expected<std::vector<ScriptAction>> read_script(const std::filesystem::path& path);
/// The same from text (`name` is used in errors).
[[nodiscard]] Expected<std::vector<ScriptAction>> parse_script(const std::string& text, const std::string& name);

}  // namespace hof::app
