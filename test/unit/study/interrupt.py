class Interrupt:
    """A progress printer that stops the study (like Ctrl-C) after `chunks` chunks."""

    def __init__(self, chunks):
        self.chunks = chunks

    def line(self, text):
        pass

    def begin(self, done=0):
        pass

    def count(self, done, total, unit=''):
        self.chunks -= 1
        if self.chunks == 0:
            raise KeyboardInterrupt

