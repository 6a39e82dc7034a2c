#!/usr/bin/env bash
# sigrok-cli for tests/identify (a vfgym VCD round-tripped through `sigrok-cli -I vcd -O vcd`).
#
#   source .ci/sigrok.sh     # installs Debian's sigrok-cli with apt when it is missing
#
# Without root (or apt) it only says so: the round-trip test then skips, naming the reason.

_vfgym_sigrok_main() {
  if command -v sigrok-cli >/dev/null 2>&1; then
    echo "sigrok.sh: $(sigrok-cli --version 2>/dev/null | head -n 1) is installed" >&2
    return 0
  fi
  if [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null 2>&1; then
    echo "sigrok.sh: sigrok-cli is not installed and installing it needs root and apt-get;" \
      "tests/identify's sigrok round trip will skip" >&2
    return 0
  fi
  echo "sigrok.sh: installing sigrok-cli (apt-get)" >&2
  DEBIAN_FRONTEND=noninteractive apt-get update -qq &&
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends sigrok-cli >/dev/null ||
    echo "sigrok.sh: apt-get could not install sigrok-cli; the round-trip test will skip" >&2
  return 0
}

_vfgym_sigrok_main "$@"
