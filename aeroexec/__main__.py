from aeroexec.cli import main

main()
