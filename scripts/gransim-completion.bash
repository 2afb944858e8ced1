# bash completion for gransim: subcommands, their options, and case files
# (*.yaml, *.yml) or folders where a file or folder is expected.  Installed as
# share/bash-completion/completions/gransim; source it to try it from a clone.
_gransim() {
  local cur prev words cword
  if declare -F _init_completion >/dev/null; then
    _init_completion -n = || return
  else
    cur=${COMP_WORDS[COMP_CWORD]}
    prev=${COMP_WORDS[COMP_CWORD - 1]}
    words=("${COMP_WORDS[@]}")
    cword=$COMP_CWORD
  fi
  local commands="run check list validate validate-cfd validate-fit plot sweep fit sensitivity optimise dem dem-reduce compartments couple geometry"
  if [ "$cword" -eq 1 ]; then
    COMPREPLY=($(compgen -W "$commands --help --version" -- "$cur"))
    return
  fi
  local opts
  case ${words[1]} in
    run) opts="--out --resume --quiet --progress --threads --timings --help" ;;
    check) opts="--help" ;;
    list) opts="" ;;
    validate) opts="--out --quick --only --threads --max-loss --help" ;;
    validate-cfd) opts="--out --long --qualitative --help" ;;
    validate-fit) opts="--out --quick --max-runs --help" ;;
    plot) opts="--times --format --out --help" ;;
    sweep) opts="--set --design --range --seed --out --outputs --at --resume --threads --quiet --progress --help" ;;
    fit) opts="--data --batches --params --global --seed --porosity-tol --max-runs --predict --out --help" ;;
    sensitivity) opts="--range --outputs --method --levels --bootstrap --conf --seed --out --resume --threads --quiet --progress --help" ;;
    optimise) opts="--target --controls --weights --method --max-runs --tol --help" ;;
    dem) opts="--out --check --quiet --threads --engine --ranks --launcher --dry-run --reduce --help" ;;
    dem-reduce) opts="--out --impacts --E --nu --rho --e --wall-E --wall-nu --contact-time --min-speed --edges --measure --prefix --contacts --help" ;;
    compartments) opts="--out --clusters --max-clusters --time-step --start --velocity-weight --seed --help" ;;
    couple) opts="--out --check --resume --quiet --threads --ranks --launcher --help" ;;
    geometry) opts="--out --help" ;;
    *) return ;;
  esac
  # --key=value: complete the value part
  if [[ $cur == --*=* ]]; then
    prev=${cur%%=*}
    cur=${cur#*=}
  fi
  case $prev in
    --out)
      if [ "${words[1]}" = validate ] || [ "${words[1]}" = validate-cfd ] || [ "${words[1]}" = validate-fit ] || [ "${words[1]}" = dem-reduce ] || [ "${words[1]}" = compartments ]; then
        COMPREPLY=($(compgen -f -- "$cur"))
      else
        COMPREPLY=($(compgen -d -- "$cur"))
      fi
      return ;;
    --data | --target | --impacts) COMPREPLY=($(compgen -f -X '!*.csv' -- "$cur") $(compgen -d -- "$cur")); return ;;
    --batches | --predict) COMPREPLY=($(compgen -f -X '!*.yaml' -- "$cur") $(compgen -d -- "$cur")); return ;;
    --method)
      case ${words[1]} in
        optimise) COMPREPLY=($(compgen -W "nelder-mead bounded" -- "$cur")) ;;
        sensitivity) COMPREPLY=($(compgen -W "sobol: morris:" -- "$cur")) ;;
      esac
      return ;;
    --measure) COMPREPLY=($(compgen -W "diameter volume" -- "$cur")); return ;;
    --engine) COMPREPLY=($(compgen -W "embedded liggghts" -- "$cur")); return ;;
    --contacts) COMPREPLY=($(compgen -W "auto ppcoll cc cc-partner" -- "$cur")); return ;;
    --design) COMPREPLY=($(compgen -W "lhs:" -- "$cur")); return ;;
    --threads | --ranks | --seed | --levels | --bootstrap | --conf | --max-runs | --tol | --max-loss | \
      --set | --range | --params | --controls | --weights | --outputs | --at | --only | --launcher | --edges | \
      --prefix | --E | --nu | --rho | --e | --wall-E | --wall-nu | --contact-time | --min-speed | \
      --clusters | --max-clusters | --time-step | --start | --velocity-weight)
      return ;;
  esac
  if [[ $cur == -* ]]; then
    COMPREPLY=($(compgen -W "$opts" -- "$cur"))
  elif [ "${words[1]}" = dem-reduce ]; then
    COMPREPLY=($(compgen -d -- "$cur"))
  elif [ "${words[1]}" = compartments ]; then
    COMPREPLY=($(compgen -f -- "$cur"))
  else
    COMPREPLY=($(compgen -f -X '!*.yaml' -- "$cur") $(compgen -f -X '!*.yml' -- "$cur") $(compgen -d -- "$cur"))
  fi
}
complete -o filenames -F _gransim gransim
