// Output paths of the CLI: checking --out folders and files before anything runs, names that
// become parts of file names, and the clean-up of staging folders and temporary files when the
// process is interrupted (SIGINT, SIGTERM, SIGHUP).
//
// Contract (README, "Exit codes"): nothing is written before the inputs are validated; a run
// writes into a staging folder `OUT.partial` and renames it onto OUT only when complete; a
// refused or interrupted run leaves neither. SIGKILL cannot be caught: its `OUT.partial` stays
// until the next run with the same --out removes it (CreateStagingDirectory).
#pragma once

#include <string>

namespace twin {

/// Writes a whole text file (into a staging folder); a failure (disk full, permissions) is an
/// InputError naming the file.
void WriteTextFile(const std::string& path, const std::string& text);

/// Refuses an output folder path before anything runs: empty, ".", "..", "/" or ending in
/// one of them, an existing path that is not a folder, or a parent that exists and is not a
/// folder. `option` names the flag in the message ("--out"). Throws InputError.
void ValidateOutputFolder(const std::string& path, const std::string& option);

/// Refuses an output file path before anything runs: empty, a folder, ending in '/', or in a
/// folder that does not exist. Throws InputError naming `option`.
void ValidateOutputFile(const std::string& path, const std::string& option);

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
