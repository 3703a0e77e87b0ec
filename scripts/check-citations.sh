#!/usr/bin/env bash
# Every citation of the model ("model.md §5", "§6.3", "§§2–4", "model.md section 6") in the
# repository's tracked files names a section docs/model.md has ("## §5 …", "### §6.3 …"), and
# nothing points outside the repository (to the shared folder beside it).
# Usage: scripts/check-citations.sh
set -euo pipefail
cd "$(dirname "$0")/.."
model=docs/model.md
sections=$(grep -oE '^#{2,3} §[0-9]+(\.[0-9]+)?' "$model" | sed 's/^#* §//' | sort -u)
has() { grep -qx "$1" <<<"$sections"; }
bad=0 n=0
while IFS=: read -r file line text; do
    # Each citation's numbers: §a, §a.b, §§a–b (both ends), "section(s) a[-b]".
    for cite in $(grep -oE 'model\.md (§§?|sections? )[0-9]+(\.[0-9]+)?([–-][0-9]+)?' <<<"$text" \
        | sed -E 's/model\.md (§§?|sections? )//'); do
        for number in ${cite//[–-]/ }; do
            n=$((n + 1))
            if ! has "$number"; then
                echo "$file:$line: model.md §$number is not a section of $model" >&2
                bad=1
            fi
        done
    done
done < <(git ls-files -z | xargs -0 grep -nE 'model\.md (§|section)' -- 2>/dev/null | grep -v "^$model:" || true)
outside='\.\./'"shared"
if git ls-files -z | xargs -0 grep -ln "$outside" -- 2>/dev/null | grep -vx "scripts/check-citations.sh"; then
    echo "the files above point outside the repository" >&2
    bad=1
fi
[ "$bad" = 0 ] && echo "model citations: $n, each a section of $model; nothing points outside the repository"
exit "$bad"
