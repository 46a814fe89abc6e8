suspend(bot)
