# Sourced by the scripts that keep a results page under docs/results/ newest first.
# insert_section DOC SECTION: SECTION's text goes above DOC's first "## " heading, below its
# title and introduction. Where DOC does not exist yet, its title and introduction are read from
# standard input. DOC is replaced whole (DOC.new, then a rename): never half-written.
insert_section() {
  local doc="$1" section="$2"
  if [ -f "$doc" ]; then
    { sed -n '1,/^## /{/^## /!p}' "$doc"; cat "$section"; sed -n '/^## /,$p' "$doc"; } >"$doc.new"
  else
    { cat; echo; cat "$section"; } >"$doc.new"
  fi
  mv "$doc.new" "$doc"
}
