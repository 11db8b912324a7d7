"""Makes `import meshmend` work in the interpreter that runs this script:
writes meshmend.pth (one line: the build's python folder) into its first
writable site folder (the system one as root, else the user's). Idempotent:
an unchanged file is left alone. Exits 2 when the built module does not fit
this interpreter (another Python version), 1 when no site folder is writable.

    python3 python/install_path.py BUILD_DIR/python
"""
import importlib.machinery
import os
import site
import sys


def main() -> int:
    target = os.path.abspath(sys.argv[1])
    package = os.path.join(target, "meshmend")
    built = [f for f in os.listdir(package) if f.startswith("_core.")] if os.path.isdir(package) else []
    if not any(f.endswith(tuple(importlib.machinery.EXTENSION_SUFFIXES)) for f in built):
        print(f"{sys.executable} (Python {sys.version.split()[0]}): meshmend is built for another "
              f"Python ({', '.join(built) or 'nothing built'}); not registered")
        return 2
    folders = list(site.getsitepackages())
    if site.ENABLE_USER_SITE:
        folders.append(site.getusersitepackages())
    line = target + "\n"
    for folder in folders:
        path = os.path.join(folder, "meshmend.pth")
        try:
            with open(path) as f:
                if f.read() == line:
                    print(f"{path}: already points at {target}")
                    return 0
        except OSError:
            pass
        try:
            os.makedirs(folder, exist_ok=True)
            with open(path, "w") as f:
                f.write(line)
        except OSError:
            continue
        print(f"{path}: now points at {target}")
        return 0
    print(f"{sys.executable}: no writable site folder among {folders}")
    return 1


if __name__ == "__main__":
    sys.exit(main())
