-- os is not available in the sandbox.
os.execute("echo hacked")
