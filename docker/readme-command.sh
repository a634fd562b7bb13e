#!/usr/bin/env bash
# Print README command N (the Nth ```bash block of README.md's "Set-up: two commands"), as written:
#
#   docker/readme-command.sh N [README]
#
# CI runs what this prints (.ci/run on the machine, docker/podman-ci.sh in a bare Debian container),
# so the commands a reader copies are the ones proven, never a copy of them.
set -euo pipefail

usage="usage: docker/readme-command.sh N [README]"
number=${1:?$usage}
readme=${2:-$(dirname "$0")/../README.md}

command=$(awk -v wanted="$number" '
    /^## / { in_setup = ($0 == "## Set-up: two commands") }
    in_setup && /^```bash$/ { block += 1; inside = 1; next }
    inside && /^```$/ { inside = 0; next }
    inside && block == wanted { print }
' "$readme")
if [ -z "$command" ]; then
    echo "README command $number not found in $readme (a \`\`\`bash block under '## Set-up: two commands')" >&2
    exit 1
fi
printf '%s\n' "$command"
