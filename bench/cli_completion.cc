#include "bench/cli_completion.h"

#include <sstream>
#include <vector>

namespace twin {
namespace {

// The names of `app`'s own options ("-h --help --out ..."); `with_value` keeps only those that
// take a value (not flags).
std::string CompletionOptionNames(const CLI::App& app, bool with_value) {
  std::string names;
  for (const CLI::Option* opt : app.get_options()) {
    if (!opt->nonpositional() || (with_value && opt->get_expected_min() == 0)) continue;
    for (const std::string& s : opt->get_snames()) names += (names.empty() ? "-" : " -") + s;
    for (const std::string& l : opt->get_lnames()) names += (names.empty() ? "--" : " --") + l;
  }
  return names;
}

std::vector<const CLI::App*> VisibleVerbs(const CLI::App& app) {
  return app.get_subcommands([](const CLI::App* sub) { return !sub->get_group().empty(); });
}

// One case of the verb's options: `  fk) opts="..."; takes="...";;`
void WriteCompletionCase(std::ostringstream& out, const std::string& pattern,
                         const std::string& opts, const std::string& takes) {
  out << "    " << pattern << ") opts=\"" << opts << "\"; takes=\"" << takes << "\";;\n";
}

}  // namespace

CLI::App* AddCompletionVerb(CLI::App* app, std::string* shell) {
  auto* sub = app->add_subcommand("completion", "print a shell completion script (bash)");
  sub->group("");  // hidden from --help
  sub->add_option("shell", *shell, "bash")->required()->check(CLI::IsMember({"bash"}));
  return sub;
}

std::string BashCompletion(const CLI::App& app) {
  const std::vector<const CLI::App*> verbs = VisibleVerbs(app);
  std::string verb_names;
  for (const CLI::App* verb : verbs) {
    verb_names += (verb_names.empty() ? "" : "|") + verb->get_name();
  }
  std::string top = CompletionOptionNames(app, false);
  for (const CLI::App* verb : verbs) top += " " + verb->get_name();

  std::ostringstream out;
  out << "# bash completion for twinbench, written by `twinbench completion bash` from its own\n"
         "# command line (bench/cli_completion.cc). Verbs, their options; file names for\n"
         "# arguments and option values.\n"
         "_twinbench() {\n"
         "  local cur=\"${COMP_WORDS[COMP_CWORD]}\" prev=\"${COMP_WORDS[COMP_CWORD-1]}\"\n"
         "  local verb=\"\" i opts takes\n"
         "  for ((i = 1; i < COMP_CWORD; i++)); do\n"
         "    case \"${COMP_WORDS[i]}\" in\n"
         "      " << verb_names << ") verb=\"${COMP_WORDS[i]}\"; break;;\n"
         "    esac\n"
         "  done\n"
         "  case \"$verb\" in\n";
  WriteCompletionCase(out, "\"\"", top, CompletionOptionNames(app, true));
  for (const CLI::App* verb : verbs) {
    WriteCompletionCase(out, verb->get_name(), CompletionOptionNames(*verb, false),
                        CompletionOptionNames(*verb, true));
  }
  out << "  esac\n"
         "  if [[ -n \"$takes\" && \" $takes \" == *\" $prev \"* ]]; then\n"
         "    COMPREPLY=($(compgen -f -- \"$cur\"))\n"
         "  elif [[ -z \"$verb\" || \"$cur\" == -* ]]; then\n"
         "    COMPREPLY=($(compgen -W \"$opts\" -- \"$cur\"))\n"
         "  else\n"
         "    COMPREPLY=($(compgen -f -- \"$cur\"))\n"
         "  fi\n"
         "}\n"
         "complete -o filenames -o bashdefault -F _twinbench twinbench\n";
  return out.str();
}

}  // namespace twin
