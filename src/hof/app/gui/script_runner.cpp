// The script runner: one action of a script (gui_script.h) per call until it must wait (a
// wait, a screenshot taken at the end of the next frame), through the window's own paths.
#include <fmt/format.h>

#include <chrono>
#include <cstdio>

#include "hof/app/gui/detail/gui_window.h"
#include "hof/app/gui/detail/panels.h"

namespace hof::app::gui {

bool GuiWindow::step_script(std::vector<ScriptAction>& script, std::size_t& next, const std::string& name,
                            int& status) {
  while (next < script.size()) {
    const ScriptAction& a = script[next];
    const auto fail = [&](const Error& e) {
      std::fprintf(stderr, "hof gui: %s:%d: '%s': %s\n", name.c_str(), a.line, a.text.c_str(), e.to_string().c_str());
      status = 1;
      return false;
    };
    switch (a.kind) {
      case ScriptAction::Kind::kWait:
        if (!script_waiting_) {
          script_waiting_ = true;
          script_wait_until_ =
              Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.number));
        }
        if (Clock::now() < script_wait_until_) return true;
        script_waiting_ = false;
        break;
      case ScriptAction::Kind::kAnimate:
        set_animating(a.on);
        break;
      case ScriptAction::Kind::kNeedle:
        if (auto ok = mount_needle(a.on); !ok) return fail(ok.error());
        break;
      case ScriptAction::Kind::kTool: {
        // Through the Tool panel's own commands.
        ToolChoice choice;
        choice.kind = a.type == "sphere"    ? ToolChoice::Kind::kSphere
                      : a.type == "capsule" ? ToolChoice::Kind::kCapsule
                      : a.type == "mesh"    ? ToolChoice::Kind::kMesh
                      : a.type == "needle"  ? ToolChoice::Kind::kNeedle
                                            : ToolChoice::Kind::kPoint;
        if (choice.kind == ToolChoice::Kind::kCapsule) {
          choice.length_m = a.numbers[0];
          choice.radius_m = a.numbers[1];
        } else if (!a.numbers.empty()) {
          choice.radius_m = a.numbers[0];
        } else if (choice.kind == ToolChoice::Kind::kMesh) {
          choice.radius_m = 0.0;  // automatic
        }
        if (choice.kind == ToolChoice::Kind::kMesh) choice.mesh = std::filesystem::absolute(a.file).string();
        if (!session_) return fail(Error{ErrorCode::kInvalidArgument, "no world is open", "", 0, -1});
        for (const GuiCommand& c : tool_commands(project_, choice)) {
          if (auto ok = apply(c); !ok) return fail(ok.error());
        }
        break;
      }
      case ScriptAction::Kind::kRotate:
        if (!mouse_)
          return fail(Error{ErrorCode::kInvalidArgument, "the stylus is not the mouse (device " + device_spec_ + ")",
                            "", 0, -1});
        turn_mouse_stylus(
            Eigen::Quaterniond(Eigen::AngleAxisd(a.numbers[3] * 3.14159265358979323846 / 180.0,
                                                 Vec3(a.numbers[0], a.numbers[1], a.numbers[2]).normalized())));
        break;
      case ScriptAction::Kind::kContacts:
        view_options_.show_contacts = a.on;
        break;
      case ScriptAction::Kind::kPair: {
        const auto index = [&](const std::string& body) -> Expected<std::int32_t> {
          for (std::size_t i = 0; i < bodies_.size(); ++i) {
            if (bodies_[i].name == body) return static_cast<std::int32_t>(i);
          }
          std::string names;
          for (const BodyView& b : bodies_) names += (names.empty() ? "" : ", ") + b.name;
          return make_error(ErrorCode::kInvalidArgument, fmt::format("no body '{}' (bodies: {})", body, names));
        };
        const auto first = index(a.element);
        if (!first) return fail(first.error());
        const auto second = index(a.attribute);
        if (!second) return fail(second.error());
        if (auto ok = apply(GuiCommand{coupling::Command{coupling::command::SetContactPair{
                static_cast<coupling::BodyId>(*first), static_cast<coupling::BodyId>(*second), a.on}}});
            !ok)
          return fail(ok.error());
        break;
      }
      case ScriptAction::Kind::kStep:
        if (session_) {
          if (auto ok = session_->submit(coupling::command::SingleStep{static_cast<int>(a.number)}); !ok)
            return fail(ok.error());
        }
        break;
      case ScriptAction::Kind::kReset:
        if (session_) (void)session_->submit(coupling::command::Reset{});
        break;
      case ScriptAction::Kind::kSet:
        if (auto ok = apply_set(a.element, a.attribute, a.value); !ok) return fail(ok.error());
        break;
      case ScriptAction::Kind::kEdit: {
        // mechanics/BODY/COMPONENT (replace, remove) or mechanics/BODY (add).
        const std::string path = a.element.substr(std::string("mechanics/").size());
        const std::size_t slash = path.find('/');
        scene::SceneEdit edit;
        edit.action = a.value == "replace" ? scene::SceneEdit::Action::kReplace
                      : a.value == "add"   ? scene::SceneEdit::Action::kAdd
                                           : scene::SceneEdit::Action::kRemove;
        edit.node = path.substr(0, slash);
        edit.component = a.value == "add" ? a.name : path.substr(slash + 1);
        edit.type = a.type;
        edit.attributes = a.attributes;
        if (auto ok = change_structure(edit, std::nullopt); !ok) return fail(ok.error());
        break;
      }
      case ScriptAction::Kind::kRegion: {
        std::vector<scene::MaterialRegion> regions;
        if (!a.numbers.empty()) {
          regions = project_.regions;
          scene::MaterialRegion r;
          r.name = fmt::format("region{}", regions.size() + 1);
          r.body = a.element;
          r.shape = a.box ? scene::MaterialRegion::Shape::kBox : scene::MaterialRegion::Shape::kSphere;
          if (a.box) {
            r.box_min = Vec3(a.numbers[0], a.numbers[1], a.numbers[2]);
            r.box_max = Vec3(a.numbers[3], a.numbers[4], a.numbers[5]);
          } else {
            r.center = Vec3(a.numbers[0], a.numbers[1], a.numbers[2]);
            r.radius = a.numbers[3];
          }
          r.young_modulus_pa = a.numbers.back();
          regions.push_back(r);
        }
        if (auto ok = change_structure(std::nullopt, regions); !ok) return fail(ok.error());
        break;
      }
      case ScriptAction::Kind::kMouse:
        if (!mouse_)
          return fail(Error{ErrorCode::kInvalidArgument, "the stylus is not the mouse (device " + device_spec_ + ")",
                            "", 0, -1});
        mouse_to(a.number, a.y, 0.0, true);
        mouse_to(a.number, a.y, a.depth, false);
        break;
      case ScriptAction::Kind::kOpen:
        // The window's own error path: shown, and the world stays as it was.
        if (auto ok = open(a.file); !ok) report(ok.error().to_string(), true);
        break;
      case ScriptAction::Kind::kShow:
        open_panel_ = a.value;
        break;
      case ScriptAction::Kind::kRecord:
        if (auto ok = a.on ? start_recording(a.file) : stop_recording(); !ok) return fail(ok.error());
        break;
      case ScriptAction::Kind::kScreenshot:
        pending_screenshot_ = a.file;
        ++next;
        return true;  // taken at the end of the next frame
      case ScriptAction::Kind::kSave:
        if (auto ok = save(a.file); !ok) return fail(ok.error());
        break;
      case ScriptAction::Kind::kQuit:
        next = script.size();
        return false;
    }
    ++next;
  }
  return false;
}

}  // namespace hof::app::gui
