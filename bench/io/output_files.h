// Output paths of the CLI: checking --out folders and files before anything runs, names that
// become parts of file names, and the clean-up of staging folders and temporary files when the
// process is interrupted (SIGINT, SIGTERM, SIGHUP).
//
// Contract (docs/reference/exit-codes-and-safety.md): nothing is written before the inputs are
// validated; a run writes into a staging folder `OUT.partial` and renames it onto OUT only when
// complete; a refused or interrupted run leaves neither. SIGKILL cannot be caught: its
// `OUT.partial` stays until the next run with the same --out removes it (CreateStagingDirectory).
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace twin {

/// Writes all of `text` to the open descriptor `fd` (retrying short writes and EINTR); false
/// with errno set when a write fails (a full disk).
bool WriteAll(int fd, const std::string& text);

/// Writes a whole text file (into a staging folder); a failure (disk full, permissions) is an
/// InputError naming the file.
void WriteTextFile(const std::string& path, const std::string& text);

/// The output-safety rule (docs/reference/exit-codes-and-safety.md): a verb writes only into a
/// folder it creates, into an empty folder, or into one it marked as its own in an earlier run; it
/// deletes nothing it did not create, and no output overlaps an input. The mark is this file in the
/// folder, a JSON object {"written_by": "twinbench", "verb": VERB}.
inline constexpr const char* kOutputMarker = ".twinbench-output";

/// The verb whose outputs this process writes ("run", "identify", ...): the marks it writes
/// and the only marks it accepts as its own. Set once by main(), before anything is written;
/// default "twinbench".
void SetOutputVerb(const std::string& verb);
const std::string& OutputVerb();

/// Records an input of this process (a file or a folder it reads). Outputs may not equal or
/// contain an input, nor lie inside an input folder (ValidateOutputFolder, ValidateOutputFile).
/// Files read through ReadInputFile / RequireInputFile (bench/io/yaml_util.h) are recorded by
/// them; main() records the inputs named on the command line.
void NoteInput(const std::string& path, bool is_folder = false);

/// True when `dir` is a folder holding the mark of `verb` (kOutputMarker).
bool IsMarkedFolder(const std::string& dir, const std::string& verb);

/// Writes the mark of OutputVerb() (or `verb` when given) into the folder `dir`.
void MarkFolder(const std::string& dir, const std::string& verb = "");

/// Refuses an output folder path before anything runs (InputError naming `option`, "--out"):
/// empty, ".", "..", "/" or ending in one of them; an existing path that is a symbolic link,
/// not a folder, or a non-empty folder without the mark of `verb` (default OutputVerb()); the
/// staging siblings PATH.partial / PATH.old where they exist without the mark; a path equal
/// to or containing an input, or inside an input folder (NoteInput). `staged`: false for a
/// folder written in place (ClaimOutputFolder), which has no staging siblings and may be
/// reached through a symbolic link.
void ValidateOutputFolder(const std::string& path, const std::string& option,
                          const std::string& verb = "", bool staged = true);

/// Creates the folder `dir` with the mark of `verb` (ValidateOutputFolder first), or accepts it
/// when it is already an empty or marked folder; for folders written in place (a study's, a
/// plan cache). Throws InputError naming `option`.
void ClaimOutputFolder(const std::string& dir, const std::string& option,
                       const std::string& verb = "");

/// Refuses an output file path before anything runs (InputError naming `option`): empty, a
/// folder, ending in '/', in a folder that does not exist or cannot be written, a symbolic
/// link, anything but a regular file (a FIFO, a device), an input (NoteInput), or an existing
/// file that holds none of `signatures` in its first 4 KiB (a file twinbench did not write;
/// with no signatures every existing file is refused).
void ValidateOutputFile(const std::string& path, const std::string& option,
                        const std::vector<std::string>& signatures = {});

/// True when `inner` is the path `outer` or lies below it (absolute, normalised, symbolic links
/// resolved as far as the paths exist).
bool PathIsWithin(const std::string& inner, const std::string& outer);

/// The comment twinbench writes into the text files it may later replace (JUnit, URDF).
inline constexpr const char* kWrittenByComment = "<!-- written by twinbench -->";

/// True for names that may become part of a file name: 1 to 64 characters of [A-Za-z0-9_],
/// not starting with a digit (no '/', '.', '..', spaces or control characters).
bool IsSafeName(const std::string& name);

/// Throws InputError(where, ...) unless IsSafeName(name); `what` says what the name is
/// ("robot name").
void RequireSafeName(const std::string& name, const std::string& where, const std::string& what);

/// Blocks SIGINT, SIGTERM and SIGHUP in the calling thread and starts a thread that waits for
/// them; on one it removes every registered path (RegisterCleanupPath) and ends the process by
/// that signal. Call first thing in main(), before any other thread exists (threads inherit
/// the mask). Idempotent.
void InstallInterruptCleanup();

/// Replaces the default reaction to SIGINT, SIGTERM and SIGHUP (remove the registered paths and
/// end by the signal) by `handler(signal)`, run on the waiting thread; the process then goes on,
/// and the handler's owner ends it (EndBySignal). Used by `study`, which must stop its trial
/// processes before it cleans up. An empty handler restores the default.
void SetInterruptHandler(std::function<void(int)> handler);

/// Removes every registered path and ends the process by `sig` (default action), as an
/// interrupt does by default.
[[noreturn]] void EndBySignal(int sig);

/// Paths (staging folders, temporary files) to remove if the process is interrupted.
/// CreateStagingDirectory and WriteFileAtomically register theirs; PublishDirectory and
/// DiscardStaging unregister.
void RegisterCleanupPath(const std::string& path);
void UnregisterCleanupPath(const std::string& path);

/// Removes a staging folder (or file) and unregisters it; never throws.
void DiscardStaging(const std::string& path);

/// Runs `f` with the interrupt clean-up held off (the rename of a completed staging folder
/// onto its destination happens entirely before or entirely after a clean-up).
template <typename F>
void WithCleanupHeld(F&& f);

namespace internal {
void LockCleanup();
void UnlockCleanup();
}  // namespace internal

template <typename F>
void WithCleanupHeld(F&& f) {
  internal::LockCleanup();
  try {
    f();
  } catch (...) {
    internal::UnlockCleanup();
    throw;
  }
  internal::UnlockCleanup();
}

}  // namespace twin
