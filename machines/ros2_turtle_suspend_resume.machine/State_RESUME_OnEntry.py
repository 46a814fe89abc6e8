resume(bot)
