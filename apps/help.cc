#include "apps/help.h"

#include <algorithm>
#include <cctype>
#include <map>
#include <sstream>

#include <opencv2/core/version.hpp>

#include "omma/core/version.h"
#include "omma/render/render.h"

#ifndef OMMA_BUILD_TYPE
#define OMMA_BUILD_TYPE "unknown"
#endif
#ifndef OMMA_MPI_BUILT
#define OMMA_MPI_BUILT 0
#endif
#ifndef OMMA_RTL_BUILT
#define OMMA_RTL_BUILT 0
#endif
#ifndef OMMA_GSTREAMER_BUILT
#define OMMA_GSTREAMER_BUILT 0
#endif
#ifndef OMMA_PYTHON_BUILT
#define OMMA_PYTHON_BUILT 0
#endif

namespace omma::app {
namespace {

// Every command's examples: real command lines that run as written from the source tree (built-in
// rig names, the simulator's scenes, files the earlier lines make). A line starting with '#' is a
// comment. Keep them short: two to four lines, the common case first.
const std::map<std::string, std::vector<const char*>>& examples_table() {
  static const std::map<std::string, std::vector<const char*>> table = {
      {"",
       {"omma demo                                  # the whole pipeline on the simulated colon",
        "omma stitch --help                         # every command has its own help",
        "omma completion bash > ~/.local/share/bash-completion/completions/omma"}},
      {"rig",
       {"omma rig check thesis-24", "omma rig new --camera size=640x480,fov=60 --out cam.json",
        "omma rig export thesis-24 --colmap colmap_model --pto rig.pto --opencv rig.yml",
        "omma rig import colmap_model --out from_colmap.json"}},
      {"rig check", {"omma rig check thesis-24", "omma rig check calibrated.json --json"}},
      {"rig new",
       {"omma rig new --camera size=640x480,fov=60 --camera size=640x480,focal=535,ypr=-90,0,180,pos=0,60,0 "
        "--out pair.json",
        "omma rig new --stereo /usr/share/doc/opencv-doc/examples/data/intrinsics.yml --size 640x480 "
        "--baseline 60 --out stereo.json --json",
        "omma rig new --camera opencv=/usr/share/doc/opencv-doc/examples/data/left_intrinsics.yml --out "
        "left.json"}},
      {"rig export",
       {"omma rig export thesis-24 --colmap colmap_model --pto rig.pto --opencv rig.yml",
        "mkdir -p colmap_bin && colmap model_converter --input_path colmap_model --output_path colmap_bin "
        "--output_type BIN",
        "omma rig export stereo.json --opencv stereo.yml --json"}},
      {"rig import",
       {"omma rig import colmap_model --out from_colmap.json",
        "omma rig import project/sparse --scale 1000 --out from_sfm.json --json   # COLMAP units in metres",
        "omma rig import rig.pto --out from_hugin.json", "omma rig import stereo.yml --out stereo.json"}},
      {"design",
       {"omma design --method max-volume --cam-size 1x1x2 --out rig.json   # the thesis prototype",
        "omma design --method cvt --aov 64 --r-virtual 18 --sphere --out cvt.json"}},
      {"coverage",
       {"omma coverage thesis-24 --distance 25", "omma coverage rig.json --map coverage.png --json"}},
      {"sweep", {"omma sweep --out sweep", "omma sweep --aov-min 40 --aov-max 90 --out sweep --json"}},
      {"optics", {"omma optics", "omma optics --focal 800 --distance 30 --json"}},
      {"plan",
       {"omma plan --table71                 # recompute the thesis's Table 7.1",
        "omma plan --cameras 44 --fps 9.5 --minutes 14 --device-size 256GB --json"}},
      {"simulate",
       {"omma simulate --rig thesis-24 --scene colon --out frames",
        "omma simulate --rig thesis-24 --scene checker --raw --out raw_frames",
        "omma simulate --rig gigaeye-44 --scene photo:../shared/data/lake.jpg --projection equirect-100 "
        "--out giga",
        "omma simulate --rig gigaeye-44-skip3 --scene room --projection equirect-100 --truth-size 1800x480 "
        "--dome-at 500,0,0 --out room   # a near scene, 0.5-10 m"}},
      {"link", {"omma link encode frames/cam_00_raw.png cam0.bin", "omma link decode cam0.bin --json"}},
      {"link encode",
       {"omma link encode frames/cam_00_raw.png cam0.bin",
        "omma link encode frames/cam_00_raw.png noisy.bin --flip-rate 1e-5 --drop-rate 1e-3"}},
      {"link decode", {"omma link decode cam0.bin", "omma link decode noisy.bin --no-conceal --json"}},
      {"isp",
       {"omma isp --in frames/cam_00_raw.png --out cam_00.png",
        "omma isp --in frames/cam_00_raw.png --out cam_00.png --demosaic ah --awb whitepatch "
        "--eval frames/cam_00.png"}},
      {"calibrate",
       {"omma calibrate --rig thesis-24 --frames frames --out calibrated.json",
        "omma calibrate --rig thesis-24 --frames frames --photometric --out calibrated.json --json"}},
      {"rig-diff",
       {"omma rig-diff thesis-24 calibrated.json", "omma rig-diff frames/rig.json calibrated.json --json"}},
      {"pto",
       {"omma pto export calibrated.json rig.pto --frames frames",
        "omma pto import rig.pto > from_hugin.json"}},
      {"pto export",
       {"omma pto export calibrated.json rig.pto --frames frames",
        "nona -o pano rig.pto                       # Hugin renders the same panorama"}},
      {"pto import", {"omma pto import rig.pto > from_hugin.json", "omma pto import edited.pto --json"}},
      {"real",
       {"omma real stitch leuven --out real_out", "omma real depth --json",
        "scripts/real_images.sh                    # every case into docs/results/real_images.md"}},
      {"real stereo-calib",
       {"omma real stereo-calib --out real_out", "omma real stereo-calib --no-peers --json"}},
      {"real depth", {"omma real depth --out real_out", "omma real depth --quick --json"}},
      {"real stitch", {"omma real stitch leuven --out real_out", "omma real stitch graf --no-peers --json"}},
      {"stitch",
       {"omma stitch --rig thesis-24 --frames frames --out pano.png",
        "omma stitch --rig calibrated.json --frames frames --method linear --projection equirect "
        "--size 1920x480 --out pano.jpg",
        "omma stitch --rig thesis-24 --frames frames --depth estimate --depth-out depth.png --out pano.png"}},
      {"view3d",
       {"omma stitch --rig thesis-24 --frames frames --depth estimate --ply cloud.ply --depth-pano depth.png "
        "--out pano.jpg",
        "omma view3d cloud.ply --out view3d        # open view3d/index.html: drag to turn, wheel to zoom"}},
      {"eval",
       {"omma eval --pano pano.png --truth frames/truth.png",
        "omma eval --pano pano.png --truth frames/truth.png --rig thesis-24 --json"}},
      {"resolution",
       {"omma resolution --rig thesis-24", "omma resolution --rig thesis-24 --method mrf --json"}},
      {"render",
       {"omma render giga --rig gigaeye-44 --size 9000x2400 --out pano.tif",
        "omma render rec --rig gigaeye-44 --out out/pano_{set}.jpg --size 4000x1000",
        "mpirun -np 4 omma render rec --size 17700x4650 --split tiles --out big.tif",
        "omma render room --size 9000x2400 --depth estimate --out near.tif   # near scene: depth per frame "
        "set"}},
      {"refocus",
       {"omma refocus --rig thesis-24 --frames frames --focus 15 20 40 --out refocus.png --stack stack.png",
        "omma refocus --rig gigaeye-44-skip3 --frames room --focus 1410 --combine median --projection "
        "equirect-100 --size 1800x500 --out through_grid.png",
        "omma refocus --rig thesis-24 --frames frames --focus-depth estimate --out all_in_focus.png"}},
      {"record",
       {"omma record --rig thesis-24 --source sim:colon --duration 3 --out rec",
        "omma record --rig thesis-24 --source sim:checker --frames 30 --fps 20 --out rec --json"}},
      {"recording", {"omma recording check rec", "omma recording check rec --json"}},
      {"recording check", {"omma recording check rec", "omma recording check rec --json"}},
      {"run",
       {"omma run --rig thesis-24 --source sim:colon --sink http:8080   # open http://127.0.0.1:8080/",
        "omma run --rig thesis-24 --source sim:colon --duration 5 --sink pano.mp4",
        "omma run --rig calibrated.json --source /dev/video{id} --sink http:8080 --depth",
        "omma run --rig thesis-24 --source sim:colon --sink rtsp://127.0.0.1:8554/pano   # ffplay the URL",
        "omma run --rig rig.json --source 'gst:rtspsrc location=rtsp://cam{id}.local/s ! decodebin' "
        "--stall-timeout 3 --sink srt://127.0.0.1:9000"}},
      {"bench",
       {"omma bench --quick", "omma bench --only render --depth --json",
        "omma bench --stream --max-readers 8   # latency through the element, RTSP and MJPEG"}},
      {"hw",
       {"omma hw simulate --rig thesis-24 --frames frames --out hw",
        "omma hw export thesis-24 hw_tables && omma hw import hw_tables imported.json"}},
      {"hw simulate",
       {"omma hw simulate --rig thesis-24 --frames frames --out hw",
        "omma hw simulate --rig thesis-24 --frames frames --set angle_bits=12 --out hw --json"}},
      {"hw sweep", {"omma hw sweep --rig thesis-24 --frames frames --target 40 --out hw_sweep"}},
      {"hw throughput", {"omma hw throughput", "omma hw throughput --rig thesis-24 --fps 30 --json"}},
      {"hw memory", {"omma hw memory", "omma hw memory --rig gigaeye-44 --json"}},
      {"hw export",
       {"omma hw export thesis-24 hw_tables",
        "omma hw export calibrated.json hw_tables --size 1080x1080 --json"}},
      {"hw import",
       {"omma hw import hw_tables imported.json", "omma hw import hw_tables back.json --compare thesis-24"}},
      {"demo",
       {"omma demo", "omma demo --scene checker --out demo_checker",
        "omma demo --rig gigaeye-44 --out giga_demo",
        "omma demo --rig gigaeye-44 --scene room --out giga_room   # near scene: depth, refocus, 3D"}},
      {"meta",
       {"omma meta pano.mp4                          # what 360-degree metadata the file carries",
        "ffmpeg -i pano.mp4 -c:v libx264 re.mp4 && omma meta re.mp4 --projection vr180"}},
      {"completion",
       {"omma completion bash > ~/.local/share/bash-completion/completions/omma",
        "source <(omma completion bash)"}},
  };
  return table;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

size_t edit_distance(const std::string& a, const std::string& b) {
  // Damerau-Levenshtein (optimal string alignment): insert, delete, substitute, swap neighbours.
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

std::vector<CLI::App*> subcommands(const CLI::App& app) {
  return const_cast<CLI::App&>(app).get_subcommands([](CLI::App*) { return true; });
}

// Options of `app` that take a value (so that the next argument is theirs, not a command).
bool takes_value(const CLI::App& app, const std::string& arg) {
  for (const CLI::App* a = &app; a != nullptr; a = a->get_parent())
    for (const CLI::Option* opt : a->get_options()) {
      if (opt->get_items_expected_max() == 0) continue;  // a flag
      for (const std::string& n : opt->get_lnames())
        if (arg == "--" + n) return true;
      for (const std::string& n : opt->get_snames())
        if (arg == "-" + n) return true;
    }
  return false;
}

}  // namespace

std::string command_path(const CLI::App& app) {
  std::string path;
  for (const CLI::App* a = &app; a->get_parent() != nullptr; a = a->get_parent())
    path = path.empty() ? a->get_name() : a->get_name() + " " + path;
  return path;
}

void add_examples(CLI::App& root) {
  const auto& table = examples_table();
  const std::string path = command_path(root);
  const auto it = table.find(path);
  // A command without examples shows none; the test Manners.ExamplesInEveryHelp names it.
  if (it == table.end()) return;
  std::string footer = "\nExamples:\n";
  for (const char* line : it->second) footer += std::string("  ") + line + "\n";
  root.footer(footer);
  for (CLI::App* sub : subcommands(root)) add_examples(*sub);
}

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  const std::string w = lower(word);
  std::string best;
  size_t best_d = std::max<size_t>(2, w.size() / 3) + 1;
  for (const std::string& c : candidates) {
    const std::string lc = lower(c);
    size_t d = edit_distance(w, lc);
    if (w.size() >= 3 && lc.rfind(w, 0) == 0) d = std::min<size_t>(d, 1);  // a prefix: "stit"
    if (d < best_d) best_d = d, best = c;
  }
  return best;
}

std::string unknown_command_error(const CLI::App& root, const std::vector<std::string>& args) {
  const CLI::App* app = &root;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--") return "";
    if (!arg.empty() && arg[0] == '-') {
      if (arg.find('=') == std::string::npos && takes_value(*app, arg)) ++i;  // skip its value
      continue;
    }
    const auto subs = subcommands(*app);
    if (subs.empty()) return "";  // a positional argument of a leaf command
    std::vector<std::string> names;
    const CLI::App* next = nullptr;
    for (const CLI::App* s : subs) {
      names.push_back(s->get_name());
      if (s->check_name(arg)) next = s;
    }
    if (next == nullptr) {
      const std::string where = command_path(*app);
      std::string msg = "unknown command '" + (where.empty() ? "" : where + " ") + arg + "'";
      const std::string near = closest_match(arg, names);
      if (!near.empty()) msg += " (did you mean '" + (where.empty() ? "" : where + " ") + near + "'?)";
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      return msg + "; the commands" + (where.empty() ? "" : " of '" + where + "'") + " are: " + list;
    }
    app = next;
  }
  return "";
}

std::string version_text() {
  std::ostringstream out;
  out << "omma " << omma::version() << "\n";
  out << "build: " << OMMA_BUILD_TYPE << ", "
      <<
#if defined(__clang__)
      "clang " << __clang_major__ << "." << __clang_minor__ << "." << __clang_patchlevel__
#elif defined(__GNUC__)
      "GCC " << __GNUC__ << "." << __GNUC_MINOR__ << "." << __GNUC_PATCHLEVEL__
#else
      "unknown compiler"
#endif
      << "\n";
  out << "OpenCV: " << CV_VERSION << "\n";
  out << "MPI (mpirun omma render): " << (OMMA_MPI_BUILT ? "yes" : "no") << "\n";
  out << "RTL co-simulation (hw/rtl): " << (OMMA_RTL_BUILT ? "yes" : "no") << "\n";
  out << "GStreamer (gst: sources, rtsp:// srt:// sinks, plugin): " << (OMMA_GSTREAMER_BUILT ? "yes" : "no")
      << "\n";
  out << "Python bindings: " << (OMMA_PYTHON_BUILT ? "yes" : "no") << "\n";
  out << "render kernel: " << render::to_string(render::best_kernel()) << " (of";
  for (render::Kernel k : {render::Kernel::kScalar, render::Kernel::kAvx2, render::Kernel::kAvx512Vnni})
    if (render::kernel_available(k)) out << " " << render::to_string(k);
  out << " on this CPU)";
  return out.str();
}

std::string bash_completion(const CLI::App& root) {
  // Per command path: the words that may follow it (subcommands and options) and the options that
  // take a value; per option with a fixed set of values (CLI11's IsMember, shown as "TEXT:{a,b}"),
  // those values. Any other value is completed as a file name.
  std::ostringstream cases, takes, values;
  std::vector<const CLI::App*> todo{&root};
  while (!todo.empty()) {
    const CLI::App* app = todo.back();
    todo.pop_back();
    const std::string path = command_path(*app);
    std::string words, with_value;
    for (const CLI::App* s : subcommands(*app)) {
      words += s->get_name() + " ";
      todo.push_back(s);
    }
    for (const CLI::Option* opt : app->get_options()) {
      if (opt->get_lnames().empty()) continue;  // a positional argument
      for (const std::string& n : opt->get_lnames()) words += "--" + n + " ";
      if (opt->get_items_expected_max() == 0) continue;  // a flag
      for (const std::string& n : opt->get_lnames()) with_value += "--" + n + " ";
      const std::string type = opt->get_type_name();
      const size_t open = type.find(":{"), close = type.rfind('}');
      if (open == std::string::npos || close == std::string::npos || close < open) continue;
      std::string choices = type.substr(open + 2, close - open - 2);
      std::replace(choices.begin(), choices.end(), ',', ' ');
      for (const std::string& n : opt->get_lnames())
        values << "    \"" << path << "|--" << n << "\") COMPREPLY=($(compgen -W \"" << choices
               << "\" -- \"$cur\")); return;;\n";
    }
    cases << "    \"" << path << "\") echo \"" << words << "\";;\n";
    takes << "    \"" << path << "\") echo \"" << with_value << "\";;\n";
  }
  std::ostringstream s;
  s << "# bash completion for omma " << omma::version() << " (generated by `omma completion bash`)\n"
    << "_omma_words() {\n  case \"$1\" in\n"
    << cases.str() << "  esac\n}\n"
    << "_omma_takes_value() {\n  case \"$1\" in\n"
    << takes.str() << "  esac\n}\n"
    << "_omma() {\n"
    << "  local cur=\"${COMP_WORDS[COMP_CWORD]}\" prev=\"${COMP_WORDS[COMP_CWORD-1]}\" path=\"\" w i\n"
    << "  # the command path: the words before the cursor that name subcommands\n"
    << "  for ((i = 1; i < COMP_CWORD; i++)); do\n"
    << "    w=\"${COMP_WORDS[i]}\"\n"
    << "    [[ \"$w\" == -* ]] && continue\n"
    << "    case \" $(_omma_words \"$path\") \" in *\" $w \"*) path=\"${path:+$path }$w\";; esac\n"
    << "  done\n"
    << "  case \"$path|$prev\" in\n"
    << values.str() << "  esac\n"
    << "  if [[ \"$prev\" == -* && \" $(_omma_takes_value \"$path\") \" == *\" $prev \"* ]]; then\n"
    << "    COMPREPLY=($(compgen -f -- \"$cur\")); return\n"
    << "  fi\n"
    << "  COMPREPLY=($(compgen -W \"$(_omma_words \"$path\")\" -- \"$cur\"))\n"
    << "  [[ ${#COMPREPLY[@]} -eq 0 ]] && COMPREPLY=($(compgen -f -- \"$cur\"))\n"
    << "  return 0\n"
    << "}\n"
    << "complete -o filenames -o bashdefault -F _omma omma\n";
  return s.str();
}

void add_completion_command(CLI::App& root) {
  auto* cmd = root.add_subcommand("completion",
                                  "Print a shell completion script (bash) for omma's commands and options");
  static std::string shell = "bash";
  cmd->add_option("SHELL", shell, "The shell (only bash)")->check(CLI::IsMember({"bash"}));
  CLI::App* top = &root;
  cmd->callback([top] { std::fputs(bash_completion(*top).c_str(), stdout); });
}

}  // namespace omma::app
