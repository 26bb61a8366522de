#!/usr/bin/env bash
# The repository is all a user has (issue #28 item 5): no doc, scene, source or script may point at
# files outside it (the project's shared folder beside a developer's checkout). Reference values and
# formulas the docs rely on live in docs/reference/ and scenes/reference/.
#   tests/docs/self_contained.sh REPOSITORY_ROOT
set -u
cd "${1:?repository root}" || exit 2
pattern='\.\./shared|shared/(reference|design|hooks)'
hits="$(grep -rInE "$pattern" README.md docs scenes tools tests sph fsi geometry bench CMakeLists.txt \
  --exclude=self_contained.sh 2>/dev/null)"
if [[ -n "$hits" ]]; then
  echo "references outside the repository:"
  echo "$hits"
  exit 1
fi
# Every relative Markdown link in README.md and docs/ must name a file of the repository.
missing=0
while IFS=: read -r file link; do
  target="$(dirname "$file")/${link%%#*}"
  [[ -e "$target" ]] || { echo "$file: link to $link: no such file"; missing=1; }
done < <(grep -oE '\]\([^)#:]+(#[^)]*)?\)' README.md docs/*.md | sed -E 's/\]\(([^)]*)\)/\1/')
[[ $missing == 0 ]] || exit 1
echo "no reference outside the repository; every relative Markdown link resolves"
