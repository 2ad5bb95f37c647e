// A recording of a run's exchanges with its cell (`twinbench run --record RDIR`,
// bench/runs/recording_cell.h; played back by `twinbench replay RDIR`,
// bench/runs/replay_cell.h) as a file format (docs/reference/recording.md):
//   RDIR/recording.json    what was run: format, version, protocol, the scenario (path and
//                          content), trial, the run options, start (and, once the run is over,
//                          end and the number of exchanges)
//   RDIR/exchanges.jsonl   one line per call of the cell, in order:
//                          {"seq": n, "method": M, "t_wall_s": s, "request": {...},
//                           "response": {...}}
//                          request and response are the protocol's messages (twinbench.cell.v1;
//                          Truth: twinbench.bench.v1.TwinTruth) in protobuf's JSON mapping,
//                          copied into the line as protobuf printed them (never re-printed, so
//                          every double reads back to the same bits)
//   RDIR/images/NNNNNN.png the image of exchange seq NNNNNN (the response holds "image_file"
//                          in place of the PNG bytes)
#pragma once

#include <string>

namespace twin {

inline constexpr const char* kRecordingFormat = "twinbench-cell-recording";
inline constexpr int kRecordingVersion = 1;
inline constexpr const char* kRecordingProtocol = "twinbench.cell.v1";
inline constexpr const char* kRecordingManifestFile = "recording.json";
inline constexpr const char* kRecordingExchangesFile = "exchanges.jsonl";
inline constexpr const char* kRecordingImagesFolder = "images";

/// recording.json: what was recorded, enough to run the same procedure again.
struct RecordingManifest {
  std::string scenario_path;  ///< the scenario file as `run` was given it (reports name it)
  std::string scenario_dir;   ///< its folder, absolute: model paths are relative to it
  std::string scenario_text;  ///< the scenario file's content as the run read it
  int trial = 0;              ///< --trial
  bool diagnosis = true;      ///< false: --no-diagnosis
  bool images = true;         ///< false: --no-images
  std::string plan_cache;     ///< --plan-cache (information: a replay plans afresh)
  std::string cell;           ///< --cell (empty: the scenario's twin in the recording process)
  std::string started_utc;    ///< ISO 8601, when the recording started
  std::string twinbench;      ///< the recording program's version and git describe
  /// Written when the run has made its last call (RecordingCell::Finish): a recording
  /// without them is partial (the run stopped midway).
  bool complete = false;
  long exchanges = 0;
  std::string ended_utc;
};

/// The text of recording.json.
std::string RecordingManifestText(const RecordingManifest& manifest);
/// Reads recording.json's text; throws InputError naming `where` for a malformed file, another
/// format, or a newer version than kRecordingVersion.
RecordingManifest ParseRecordingManifest(const std::string& text, const std::string& where);

/// One exchange: a call of the cell and its answer.
struct RecordedExchange {
  long seq = 0;               ///< 1, 2, ...: the line number in exchanges.jsonl
  std::string method;         ///< the protocol's rpc name ("MoveTo", "GrabImage", ...; "Truth")
  double t_wall_s = 0;        ///< when the call began, seconds since the recording started
  std::string request_json;   ///< the request message, protobuf JSON (no session_id)
  std::string response_json;  ///< the response message, protobuf JSON (no image bytes)
  std::string image_file;     ///< "images/NNNNNN.png" for an image response, else empty
};

/// The line of `exchange` in exchanges.jsonl (no newline). image_file, when set, becomes the
/// response's last member.
std::string RecordedExchangeLine(const RecordedExchange& exchange);
/// Reads one line; request_json / response_json are the exact texts of the line (the response
/// without image_file). Throws InputError naming `where` for a malformed line.
RecordedExchange ParseRecordedExchangeLine(const std::string& line, const std::string& where);

}  // namespace twin
