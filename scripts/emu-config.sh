# Sourced by the timing scripts: writes a snaked configuration for N modules of
# snake-emu at 127.0.0.1:BASE.., sidewinding at once, its socket in DIR.
#   emu_config FILE BASE N DIR [EXTRA_TOML]
emu_config() {
    local file=$1 base=$2 n=$3 dir=$4 extra=${5:-}
    cat > "$file" <<TOML
$extra
[network]
targets = ["127.0.0.1:$base-$((base + n - 1))"]
expected_modules = $n
[gait]
initial = "sidewinding"
start = "run"
[control]
socket = "$dir/snaked.sock"
TOML
}
