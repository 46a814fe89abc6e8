ros.init()  # so that ros.ok() is true before the bot has run its own INITIAL
suspend(bot)
