#!/bin/sh
# Print the path of a Python interpreter of version $1 (e.g. 3.12) that really runs:
# pythonX.Y on PATH (a pyenv shim counts only if it works), then pyenv's own versions, then
# /usr/bin and /usr/local/bin. Prints nothing and exits 1 when there is none.
version="$1"
want="import sys; sys.exit(sys.version_info[:2] != tuple(map(int, '$version'.split('.'))))"
root=$(pyenv root 2>/dev/null || echo "${PYENV_ROOT:-$HOME/.pyenv}")
for candidate in "$(command -v "python$version")" \
    $(ls -d "$root"/versions/"$version".*/bin/"python$version" 2>/dev/null | sort -V -r) \
    "/usr/bin/python$version" "/usr/local/bin/python$version"; do
  if [ -n "$candidate" ] && "$candidate" -c "$want" >/dev/null 2>&1; then
    # a pyenv shim resolves through the current pyenv version: report the real interpreter
    "$candidate" -c 'import sys; print(sys.executable)'
    exit 0
  fi
done
exit 1
