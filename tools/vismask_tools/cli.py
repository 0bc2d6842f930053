"""The report scripts' shared arguments: one spelling for each, everywhere.

  --quick     the same pipeline at a small scale, in seconds to a few
              minutes: a check of the tool itself, not figures to publish
  --out DIR   where results go (each script says its default)
  -h, --help  the script's docstring"""

import sys


class Args:
    def __init__(self):
        self.quick = False
        self.out = None
        self.flags = set()  # the script's own flags that were given
        self.positional = []


def parse(argv, doc, flags=(), positional=0):
    """Parses argv[1:]: --quick, --out DIR, --help, the script's own
    value-less `flags` and up to `positional` other arguments. Anything else
    is an error (exit 2) naming the argument."""
    a = Args()
    i = 1
    while i < len(argv):
        x = argv[i]
        if x == "--quick":
            a.quick = True
        elif x == "--out":
            if i + 1 >= len(argv):
                usage_error(argv[0], "--out needs a directory")
            a.out = argv[i + 1]
            i += 1
        elif x in ("-h", "--help"):
            print(doc.strip())
            sys.exit(0)
        elif x in flags:
            a.flags.add(x)
        elif not x.startswith("-") and len(a.positional) < positional:
            a.positional.append(x)
        else:
            usage_error(argv[0], f"unknown argument '{x}' (try --help)")
        i += 1
    return a


def usage_error(prog, msg):
    print(f"{prog}: {msg}", file=sys.stderr)
    sys.exit(2)
