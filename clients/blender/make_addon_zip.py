#!/usr/bin/env python3
"""Makes the installable add-on: OUT.zip holding skinstream_live/ with the Python package
(clients/python/skinstream) inside it, so Blender needs nothing else (Edit > Preferences >
Add-ons > Install...). Usage: make_addon_zip.py OUT.zip"""
import os
import sys
import zipfile

HERE = os.path.dirname(os.path.abspath(__file__))
PACKAGE = os.path.join(HERE, '..', 'python', 'skinstream')


def add_tree(archive, folder, prefix):
    for name in sorted(os.listdir(folder)):
        if name.endswith('.py'):
            archive.write(os.path.join(folder, name), f'{prefix}/{name}')


def main():
    if len(sys.argv) != 2:
        sys.exit('usage: make_addon_zip.py OUT.zip')
    out = sys.argv[1]
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with zipfile.ZipFile(out, 'w', zipfile.ZIP_DEFLATED) as archive:
        add_tree(archive, os.path.join(HERE, 'skinstream_live'), 'skinstream_live')
        add_tree(archive, PACKAGE, 'skinstream_live/skinstream')
    print(f'make_addon_zip: {out}')


if __name__ == '__main__':
    main()
